// A 2D laser scanner simulated against wall segments: the one ray caster of
// `mapctl simulate` (client/sim_robot.h) and of the synthetic city of the tests
// (tests/sim/city_scenario.h). Noise-free: callers add range noise with their
// own seeded generator, so each keeps its random stream.
//
// Frames: walls and the sensor pose are in the map frame; beam angles are in
// the sensor frame (x forward, counter-clockwise). Units: metres, radians.
#ifndef MAPD_CLIENT_SIM_LASER_SIM_H_
#define MAPD_CLIENT_SIM_LASER_SIM_H_

#include <vector>

#include "geometry/segment2.h"

namespace mapd::sim {

// A sensor (or vehicle) pose in the ground plane.
struct Pose2 {
  geometry::Vec2 t = geometry::Vec2::Zero();            // metres, map frame
  double yaw_rad = 0.0;                                 // counter-clockwise from the map x axis
  geometry::Vec2 Apply(const geometry::Vec2& p) const;  // sensor frame -> map frame
};

// The beams of one scan: beam k points at start_rad + (k + beam_offset) * step_rad
// in the sensor frame. A full circle of N beams at sector centres is
// start -pi, step 2 pi / N, offset 0.5; a fan of N beams from -fov/2 to +fov/2 is
// start -fov/2, step fov / (N - 1), offset 0.
// REQUIRES: step_rad > 0, beams >= 0, and the fan spans less than one turn
// ((beams - 1 + beam_offset) * step_rad < 2 pi).
struct LaserFan {
  double start_rad = 0.0;
  double step_rad = 0.0;
  double beam_offset = 0.0;
  int beams = 0;
  double max_range_m = 0.0;  // returns beyond are dropped

  double BeamAngle(int k) const { return start_rad + (k + beam_offset) * step_rad; }
};

struct LaserScan {
  std::vector<double> range_m;  // per beam; +inf for no return within max_range_m
  std::vector<int> hit;         // per beam: index into `walls` of the wall hit, -1 for none
};

// Casts every beam of `fan` from `T_map_sensor` against `walls` and keeps the
// nearest hit. Ties go to the lower wall index. Each wall is rasterised into
// the beams its angular extent covers, so the cost is walls + beams covered,
// not walls x beams.
LaserScan CastLaser(const std::vector<geometry::Segment2>& walls, const Pose2& T_map_sensor,
                    const LaserFan& fan);

}  // namespace mapd::sim

#endif  // MAPD_CLIENT_SIM_LASER_SIM_H_
