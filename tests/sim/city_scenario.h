// A synthetic urban world for the fusion benchmark (issue item 6; the paper's
// PreScan world, feature-fusion paper (Li et al. 2023) section 4.2, Figure 12): a grid of
// city blocks separated by roads, one rectangular building per block or a pair
// of buildings 1-2 m apart, short trivial structures (fences, poles) between the
// road and the buildings, and a vehicle that drives every road with a 2D LiDAR
// (Gaussian range noise). Each scan is cut into line features (extraction.h)
// and placed in the map with the vehicle pose, optionally disturbed by pose
// noise. Everything is a function of ScenarioParams, seed included: the same
// parameters give the same world and the same scans, bit for bit.
//
// A multi-beam LiDAR with plane features in this world is test support in
// tests/sim (city_world.h; docs/planes-3d.md).
#ifndef MAPD_SIM_CITY_SCENARIO_H_
#define MAPD_SIM_CITY_SCENARIO_H_

#include <cstdint>
#include <vector>

#include "client/sim/laser_sim.h"
#include "fusion/engine.h"
#include "geometry/segment2.h"

namespace mapd::fusion::scenario {

struct ScenarioParams {
  uint64_t seed = 1;
  // World.
  int blocks_x = 8;
  int blocks_y = 6;
  double block_m = 40.0;         // block side
  double road_m = 12.0;          // road width (roads also run round the edge)
  double setback_m = 3.0;        // buildings keep this far from the block edge
  double close_pair_prob = 0.4;  // share of blocks holding two buildings side by side
  double close_gap_min_m = 1.0;  // gap between the buildings of a pair
  double close_gap_max_m = 2.0;
  double aligned_prob = 0.5;  // share of blocks aligned with the road grid
  double max_yaw_rad = 0.12;  // the other blocks are turned by up to this
  int fences_per_block = 2;   // 1.5-3 m fences, 1.5 m inside the block edge
  int poles_per_block = 2;    // 0.3 m square poles, 0.5 m inside the block edge
  // Vehicle and sensor.
  double scan_spacing_m = 1.0;  // route distance between scans
  int beams = 720;              // over 360 degrees
  double max_range_m = 40.0;
  double range_sigma_m = 0.02;   // Gaussian range noise
  double pose_sigma_xy_m = 0.0;  // per-scan pose error (GNSS/INS-like, independent)
  double pose_sigma_yaw_rad = 0.0;
  // Line extraction (client/robot/split_and_merge.h; the variant set in city_scenario.cc).
  double split_m = 0.08;      // split-and-merge: max point-to-chord distance
  double break_base_m = 0.3;  // consecutive points farther apart than
  double break_factor = 4.0;  //   base + factor * r * beam_angle start a new run
  int min_points = 8;         // >= 2
  double min_length_m = 0.5;
};

using Pose2 = sim::Pose2;  // the vehicle pose, the sensor at its origin

enum class StructureKind { kWall, kTrivial };

struct Structure {
  geometry::Segment2 segment;  // map frame
  StructureKind kind = StructureKind::kWall;
  int building = -1;  // walls: index into World::buildings
};

// A building corner: wall `in` ends here and wall `out` starts here.
struct Corner {
  geometry::Vec2 point = geometry::Vec2::Zero();
  int in = -1;  // structure indices
  int out = -1;
};

struct World {
  std::vector<Structure> structures;                   // walls first, then trivial structures
  size_t wall_count = 0;                               // structures[0, wall_count) are walls
  std::vector<std::vector<geometry::Vec2>> buildings;  // 4 corners each, counter-clockwise
  std::vector<Corner> corners;
  std::vector<std::pair<int, int>> close_pairs;  // building indices, gap 1-2 m
  std::vector<Pose2> route;                      // one true pose per scan
  geometry::Vec2 min = geometry::Vec2::Zero();   // bounding box, metres
  geometry::Vec2 max = geometry::Vec2::Zero();
};

struct Scan {
  ObservationId observation = 0;  // index + 1
  RobotId robot = 0;
  Pose2 true_pose;
  Pose2 estimated_pose;                 // what the features were placed with
  std::vector<GroundFeature> features;  // map frame (estimated pose); ids (index << 10) | k
  std::vector<int> truth;               // per feature: the structure most of its points hit
};

World GenerateWorld(const ScenarioParams& params);

// Simulates scans of a world; Scan(k) depends only on (params, world, k).
class ScanSimulator {
 public:
  ScanSimulator(const ScenarioParams& params, const World& world);
  size_t size() const { return world_.route.size(); }
  Scan Simulate(size_t index) const;
  // The noisy ranges of scan `index` (beam b at angle -pi + (b + 0.5) 2 pi / beams
  // in the sensor frame), +inf for no return, and the structure each beam hit (-1).
  void Ranges(size_t index, std::vector<double>* ranges, std::vector<int>* hits) const;

 private:
  const ScenarioParams params_;
  const World& world_;
  sim::LaserFan fan_;
  double cell_m_;
  std::vector<std::vector<int>> cells_;  // structure indices by cell
  int cells_x_ = 0;
  int cells_y_ = 0;
};

}  // namespace mapd::fusion::scenario

#endif  // MAPD_SIM_CITY_SCENARIO_H_
