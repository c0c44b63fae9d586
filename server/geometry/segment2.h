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

// Distance from point p to the closed segment s (clamped to the endpoints), metres.
double PointSegmentDistance(const Vec2& p, const Segment2& s);

}  // namespace mapd::geometry

#endif  // MAPD_GEOMETRY_SEGMENT2_H_
