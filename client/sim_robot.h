// A deterministic simulated robot for demos and tests: a floor of walls, a
// robot driving a closed loop, a 2D laser ray-cast against the walls, and
// split-and-merge line extraction per scan (client/sim/laser_sim.h and
// client/robot/split_and_merge.h, shared with the tests' synthetic city).
// Everything random comes from one seeded std::mt19937_64, so a seed gives the
// same batches on every run.
//
// Frames: the world (walls, robot poses) is the map frame; extracted lines are
// in the sensor frame (x forward, y left, z = 0); the sensor sits at the robot's
// origin, so T_frame_sensor is the robot pose. Units: metres, radians.
#ifndef MAPD_CLIENT_SIM_ROBOT_H_
#define MAPD_CLIENT_SIM_ROBOT_H_

#include <cstdint>
#include <random>
#include <string>
#include <vector>

#include "client/sim/laser_sim.h"
#include "geometry/segment2.h"
#include "mapserver/v1/map_service.pb.h"

namespace mapd::client {

using geometry::Segment2;
using geometry::Vec2;
using sim::Pose2;

// The default world: a 20 m x 12 m floor (corner at the origin) with three
// interior wall stubs and a 2 m x 1.5 m box in the middle; the robot loop runs
// around the box, 1 m clear of every wall.
struct SimWorld {
  std::vector<Segment2> walls;  // ground truth, map frame
  std::vector<Vec2> loop;       // closed path the robots drive, map frame
};
SimWorld DefaultWorld();

struct LaserParams {
  int beams = 180;
  double fov_rad = 3.14159265358979323846;  // centred on the x axis
  double max_range_m = 10.0;
  double range_noise_m = 0.01;  // Gaussian sigma
};

struct ExtractionParams {
  int min_points = 5;               // per segment
  double split_threshold_m = 0.05;  // max point-to-chord distance before splitting
  double min_length_m = 0.3;        // shorter segments are dropped
  // Consecutive points further apart than min_gap_m + gap_factor * range *
  // beam spacing start a new run (doorways, occlusion edges).
  double min_gap_m = 0.2;
  double gap_factor = 4.0;
};

// Buildings change: from the first scan after this robot has driven
// `after_laps` loops, the walls at indices `remove` (into SimWorld::walls) are
// gone and the walls `add` stand (a partition taken down, a door closed).
struct WorldChange {
  double after_laps = 1.0;
  std::vector<size_t> remove;
  std::vector<Segment2> add;
};

struct SimRobotParams {
  std::string robot_id = "sim-robot-1";
  std::string session_id = "sim";
  uint64_t first_seq = 1;
  uint64_t seed = 1;
  double start_fraction = 0.0;  // where on the loop it starts, [0, 1)
  double step_m = 0.2;          // distance driven between scans
  int64_t start_stamp_ns = 0;   // stamp of the first scan
  int64_t scan_period_ns = 100'000'000;
  LaserParams laser;
  ExtractionParams extraction;
  bool has_change = false;  // apply `change`
  WorldChange change;
};

// Ranges of one scan, beam i at angle -fov/2 + i * fov / (beams - 1) in the
// sensor frame; a beam with no wall within max range is NaN.
std::vector<double> CastScan(const std::vector<Segment2>& walls, const Pose2& T_map_sensor,
                             const LaserParams& laser, std::mt19937_64* rng);

// The scan's lines in beam order, sensor frame: the robot library's
// extractor (client/robot/laser_lines.h) with these settings.
std::vector<Segment2> ExtractSegments(const std::vector<double>& ranges, const LaserParams& laser,
                                      const ExtractionParams& params);

class SimRobot {
 public:
  SimRobot(SimWorld world, SimRobotParams params);

  // Drives one step, scans, extracts, and returns the batch (pose + lines).
  mapserver::v1::ObservationBatch NextBatch();

  // The pose the next batch will be taken from.
  Pose2 pose() const;
  // Whether params.change has been applied (before the last batch).
  bool changed() const { return changed_; }
  const SimWorld& world() const { return world_; }

 private:
  Pose2 PoseAt(double distance_m) const;

  SimWorld world_;
  SimRobotParams params_;
  std::mt19937_64 rng_;
  double loop_length_m_ = 0;
  double travelled_m_ = 0;
  double driven_m_ = 0;  // since the first scan (travelled_m_ starts at start_fraction)
  bool changed_ = false;
  uint64_t scans_ = 0;
};

}  // namespace mapd::client

#endif  // MAPD_CLIENT_SIM_ROBOT_H_
