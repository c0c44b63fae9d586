// Generated voxel submaps with ground truth for the merge tests: an indoor
// scene made of axis-aligned boxes (rooms seen from inside, furniture seen
// from outside), rasterised into OctoMap trees in a submap frame moved by a
// known rigid transform and cropped to a region, with free space (inside a
// room, outside the furniture) and unknown space (everything else). The .bt
// bytes go through the same safe reader as uploads.
#ifndef MAPD_TESTS_VOXEL_SUPPORT_VOXEL_SCENE_H_
#define MAPD_TESTS_VOXEL_SUPPORT_VOXEL_SCENE_H_

#include <Eigen/Geometry>
#include <string>
#include <vector>

namespace mapd::testing {

// An axis-aligned box of the scene, metres.
struct SceneBox {
  Eigen::Vector3d min_m, max_m;
  bool room = false;  // true: seen from inside (its interior is free)
};

struct VoxelScene {
  std::vector<SceneBox> boxes;
  // Shell half thickness in voxels: a voxel is occupied when its centre lies
  // within this distance of a box surface.
  double half_thickness_voxels = 0.55;
};

enum class SceneState { kUnknown, kFree, kOccupied };

// The scene's state at a point (metres, scene frame), for voxels of `resolution_m`.
SceneState StateAt(const VoxelScene& scene, const Eigen::Vector3d& p_scene, double resolution_m);

// Box coordinates below are shifted by +0.05 m on every axis (faces through
// the voxel centres of a 0.1 m grid, one voxel thick when axis-aligned).
// A room of 9 x 4.5 x 2.5 m with six pieces of furniture of different sizes
// at irregular places (no symmetry that would give two good matches).
VoxelScene FurnishedRoom();
// The resolution the tests rasterise FurnishedRoom at (metres).
constexpr double kRoomResolutionM = 0.1;
// FurnishedRoom cut along x (scene frame, metres): all of its y and z.
Eigen::AlignedBox3d RoomCropX(double x0, double x1);
// Another room (7.2 x 5.6 x 3.1 m) with different furniture.
VoxelScene OtherRoom();
// A single flat wall (no corners).
VoxelScene FlatWall();
// Outdoors, roughly: 40 x 40 m of terraced ground (5 m squares, 0-0.8 m
// high), free up to 12 m, with 90 trunks and bushes (0.4-1.6 m across,
// 0.5-5 m tall) at pseudo-random places, 4 m apart on average: clutter that
// a coarse cell blurs into a carpet. Crop it above z = -1 (the terraces'
// bottoms and the free room's floor lie below).
VoxelScene Grove();

// Rasterises the part of `scene` inside `crop_scene` (scene frame, metres)
// into a tree in the submap frame: voxel centre c (submap frame) gets
// StateAt(T_scene_submap * c). Returns the .bt bytes.
std::string RasteriseSubmap(const VoxelScene& scene, const Eigen::AlignedBox3d& crop_scene,
                            const Eigen::Isometry3d& T_scene_submap, double resolution_m);

// A rigid transform from yaw, pitch, roll (degrees) and a translation (metres).
Eigen::Isometry3d Pose(double yaw_deg, double pitch_deg, double roll_deg, const Eigen::Vector3d& t);

}  // namespace mapd::testing

#endif  // MAPD_TESTS_VOXEL_SUPPORT_VOXEL_SCENE_H_
