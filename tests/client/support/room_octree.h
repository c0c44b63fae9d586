// Small generated OctoMap maps for the submap end-to-end tests: a room with a
// few boxes seen from its middle (map A), a crop of the same room seen in
// another frame (map B, moved by a known transform), and a bare floor that
// has no corner to match (a merge with it must be refused).
#ifndef MAPD_TESTS_CLIENT_SUPPORT_ROOM_OCTREE_H_
#define MAPD_TESTS_CLIENT_SUPPORT_ROOM_OCTREE_H_

#include <string>

#include <Eigen/Geometry>

namespace mapd::testing {

struct RoomMapsOptions {
  double resolution_m = 0.1;
  double crop_x_min_m = 3.0;    // B sees the part of the room with x >= this (frame A)
  double yaw_deg = 20.0;        // T_a_b: rotation about z ...
  Eigen::Vector3d translation_m{3.0, -0.5, 0.0};  // ... then this translation
};

struct RoomMaps {
  std::string a_bt;   // .bt file bytes: the whole room, frame A
  std::string b_bt;   // the crop, frame B
  std::string floor_bt;  // a 4 m x 4 m floor, no walls
  Eigen::Isometry3d T_a_b = Eigen::Isometry3d::Identity();  // maps B into A
};

// Deterministic (no randomness): surfaces sampled every resolution / 2,
// inserted as one point cloud per map with ray casting from a sensor in the
// room, so that the maps hold free space as well as occupied voxels.
RoomMaps MakeRoomMaps(const RoomMapsOptions& options = {});

}  // namespace mapd::testing

#endif  // MAPD_TESTS_CLIENT_SUPPORT_ROOM_OCTREE_H_
