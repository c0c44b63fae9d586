#include "client/sim/laser_sim.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

namespace mapd::sim {

using geometry::Segment2;
using geometry::Vec2;

namespace {

double Cross(const Vec2& u, const Vec2& v) { return u.x() * v.y() - u.y() * v.x(); }

// Casts the beams [first, last] against one wall, keeping the nearest hit.
void CastBeams(const Segment2& wall, int index, const Pose2& pose, const LaserFan& fan, int first,
               int last, LaserScan* scan) {
  const Vec2 d = wall.b - wall.a;
  for (int beam = std::max(0, first); beam <= std::min(fan.beams - 1, last); ++beam) {
    const double ang = pose.yaw_rad + fan.start_rad + (beam + fan.beam_offset) * fan.step_rad;
    const Vec2 dir(std::cos(ang), std::sin(ang));
    const double den = Cross(dir, d);
    if (den == 0.0) continue;
    const double t = Cross(wall.a - pose.t, d) / den;    // along the ray
    const double u = Cross(wall.a - pose.t, dir) / den;  // along the wall
    if (t <= 0.0 || t > fan.max_range_m || u < 0.0 || u > 1.0) continue;
    if (t < scan->range_m[static_cast<size_t>(beam)]) {
      scan->range_m[static_cast<size_t>(beam)] = t;
      scan->hit[static_cast<size_t>(beam)] = index;
    }
  }
}

}  // namespace

Vec2 Pose2::Apply(const Vec2& p) const {
  const double c = std::cos(yaw_rad), s = std::sin(yaw_rad);
  return t + Vec2(c * p.x() - s * p.y(), s * p.x() + c * p.y());
}

LaserScan CastLaser(const std::vector<Segment2>& walls, const Pose2& pose, const LaserFan& fan) {
  LaserScan scan;
  const size_t beams = static_cast<size_t>(std::max(0, fan.beams));
  scan.range_m.assign(beams, std::numeric_limits<double>::infinity());
  scan.hit.assign(beams, -1);
  // Fractional beam index of a direction (map frame, relative to the sensor).
  const auto beam_of = [&](const Vec2& v) {
    double ang = std::atan2(v.y(), v.x()) - pose.yaw_rad - fan.start_rad;  // [0, 2 pi) after wrap
    ang = std::fmod(ang, 2.0 * M_PI);
    if (ang < 0.0) ang += 2.0 * M_PI;
    return ang / fan.step_rad - fan.beam_offset;
  };
  for (size_t w = 0; w < walls.size(); ++w) {
    const Segment2& wall = walls[w];
    if (geometry::PointSegmentDistance(pose.t, wall) > fan.max_range_m) continue;
    const Vec2 a = wall.a - pose.t, b = wall.b - pose.t;
    double fa = beam_of(a), fb = beam_of(b);
    if (Cross(a, b) < 0.0) std::swap(fa, fb);  // sweep counter-clockwise from fa to fb
    const int index = static_cast<int>(w);
    const int first = static_cast<int>(std::ceil(fa));
    if (fb >= fa) {
      CastBeams(wall, index, pose, fan, first, static_cast<int>(std::floor(fb)), &scan);
    } else {  // the sweep passes the start of the fan
      CastBeams(wall, index, pose, fan, first, fan.beams - 1, &scan);
      CastBeams(wall, index, pose, fan, 0, static_cast<int>(std::floor(fb)), &scan);
    }
  }
  return scan;
}

}  // namespace mapd::sim
