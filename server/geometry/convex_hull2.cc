#include "geometry/convex_hull2.h"

#include <algorithm>

namespace mapd::geometry {
namespace {

// > 0 when o -> a -> b turns left.
double Cross(const Vec2& o, const Vec2& a, const Vec2& b) {
  return (a.x() - o.x()) * (b.y() - o.y()) - (a.y() - o.y()) * (b.x() - o.x());
}

}  // namespace

std::vector<Vec2> ConvexHull(std::vector<Vec2> points) {
  const auto less = [](const Vec2& p, const Vec2& q) {
    return p.x() < q.x() || (p.x() == q.x() && p.y() < q.y());
  };
  std::sort(points.begin(), points.end(), less);
  points.erase(std::unique(points.begin(), points.end()), points.end());
  const size_t n = points.size();
  if (n <= 2) return points;

  std::vector<Vec2> hull(2 * n);
  size_t k = 0;
  for (size_t i = 0; i < n; ++i) {  // lower chain
    while (k >= 2 && Cross(hull[k - 2], hull[k - 1], points[i]) <= 0.0) --k;
    hull[k++] = points[i];
  }
  const size_t lower_size = k + 1;
  for (size_t i = n - 1; i-- > 0;) {  // upper chain
    while (k >= lower_size && Cross(hull[k - 2], hull[k - 1], points[i]) <= 0.0) --k;
    hull[k++] = points[i];
  }
  hull.resize(k - 1);  // the last point repeats the first
  return hull;
}

}  // namespace mapd::geometry
