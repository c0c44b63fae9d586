// Small OctoMap files for the submap tests of the service, mapctl, the fuzz
// seeds and the soak benchmark, generated with OctoMap itself: a room
// (floor, four walls) furnished with boxes of different sizes, cut into
// overlapping submaps seen from different frames; plus hand-made hostile
// files (truncated, garbage, too deep) built like tests/voxel/octree_reader_test.cc.
#ifndef MAPD_TESTS_COMMON_OCTOMAP_SCENES_H_
#define MAPD_TESTS_COMMON_OCTOMAP_SCENES_H_

#include <Eigen/Geometry>
#include <string>

#include "voxel/support/hostile_bt.h"  // BtHeader, BtChain for the upload tests

namespace mapd::testing {

struct RoomScene {
  double size_x_m = 10.0, size_y_m = 8.0,
         height_m = 2.5;  // the room, map frame, corner at the origin
  double resolution_m = 0.1;
  bool with_boxes = true;   // false: an empty room
  bool floor_only = false;  // a flat floor and nothing else: no corners at all
  bool with_free = true;    // mark the room's empty inside as free
  uint32_t box_seed = 0;    // 0: the fixed furniture; else random boxes from this seed
};

// The voxels of `scene` with x in [x_min_m, x_max_m) (map frame), expressed
// in a submap frame whose pose in the map frame is T_map_submap, written as a
// .bt (binary) or .ot (full) file. T_map_submap should keep voxels on the
// grid (yaw in multiples of 90 degrees, translation in whole voxels) so that
// the known transform is exact.
std::string RoomSubmap(const RoomScene& scene, double x_min_m, double x_max_m,
                       const Eigen::Isometry3d& T_map_submap, bool full_format = false);

// T_map_submap = yaw about z (radians), then translation (metres).
Eigen::Isometry3d YawTranslation(double yaw_rad, const Eigen::Vector3d& t_m);

}  // namespace mapd::testing

#endif  // MAPD_TESTS_COMMON_OCTOMAP_SCENES_H_
