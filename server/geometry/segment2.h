// 2D line segments in the map's ground plane (x-y, metres).
#ifndef MAPD_GEOMETRY_SEGMENT2_H_
#define MAPD_GEOMETRY_SEGMENT2_H_

#include <Eigen/Core>

namespace mapd::geometry {

using Vec2 = Eigen::Vector2d;

struct Segment2 {
  Vec2 a = Vec2::Zero();  // metres
  Vec2 b = Vec2::Zero();  // metres

  Vec2 direction() const { return b - a; }
  Vec2 midpoint() const { return 0.5 * (a + b); }
  double length() const { return (b - a).norm(); }
};

// The z component of u x v: |u||v| sin(angle from u to v), > 0 for a left turn.
inline double Cross(const Vec2& u, const Vec2& v) { return u.x() * v.y() - u.y() * v.x(); }
// The same for o -> a -> b: > 0 when it turns left.
inline double Cross(const Vec2& o, const Vec2& a, const Vec2& b) { return Cross(a - o, b - o); }

// Distance from point p to the closed segment s (clamped to the endpoints), metres.
double PointSegmentDistance(const Vec2& p, const Segment2& s);

}  // namespace mapd::geometry

#endif  // MAPD_GEOMETRY_SEGMENT2_H_
