#include "geometry/segment2.h"

#include <algorithm>

namespace mapd::geometry {

double PointSegmentDistance(const Vec2& p, const Segment2& s) {
  const Vec2 d = s.direction();
  const double len2 = d.squaredNorm();
  if (len2 == 0.0) return (p - s.a).norm();
  const double t = std::clamp((p - s.a).dot(d) / len2, 0.0, 1.0);
  return (p - (s.a + t * d)).norm();
}

}  // namespace mapd::geometry
