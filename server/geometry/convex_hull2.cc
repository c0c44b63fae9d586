#include "geometry/convex_hull2.h"

#include <algorithm>

namespace mapd::geometry {
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

bool StrictlyInsideHull(const std::vector<Vec2>& hull, const Vec2& p) {
  const size_t n = hull.size();
  if (n < 3) return false;
  // Edges (i - 1, i), the closing one first: no division per edge (the
  // fusion asks this of every folded feature's endpoints).
  for (size_t i = 0; i < n; ++i) {
    const Vec2& a = hull[i == 0 ? n - 1 : i - 1];
    const Vec2& b = hull[i];
    const Vec2 e = b - a, q = p - a;
    if (!(e.x() * q.y() - e.y() * q.x() > 0.0))
      return false;  // counter-clockwise: left of every edge
  }
  return true;
}

}  // namespace mapd::geometry
