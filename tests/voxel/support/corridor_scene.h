// A corridor for the correlation generator's tests: a 12 x 3 x 2.5 m room
// with one box only submap A sees, one box both see and one box only B sees,
// so that its cross-section is symmetric (the walls of a 180 deg flip
// coincide) but the free space is not. Helpers turn rasterised .bt bytes into
// the plain grids the generators take.
#ifndef MAPD_TESTS_VOXEL_SUPPORT_CORRIDOR_SCENE_H_
#define MAPD_TESTS_VOXEL_SUPPORT_CORRIDOR_SCENE_H_

#include <Eigen/Geometry>
#include <string>

#include "voxel/support/voxel_scene.h"
#include "voxel/voxel_grid.h"

namespace mapd::testing {

VoxelScene Corridor();
// A's strip x in [-0.5, 8] and B's x in [4, 12.5] (scene frame): 4 m shared.
Eigen::AlignedBox3d CorridorCropA();
Eigen::AlignedBox3d CorridorCropB();
// An empty 6 x 3 x 2.5 m room: symmetric under a 180 deg turn about z.
VoxelScene EmptyRoom();

// The grid of .bt bytes (fails the test when they do not parse).
voxel::VoxelGrid GridOf(const std::string& bt_bytes);

}  // namespace mapd::testing

#endif  // MAPD_TESTS_VOXEL_SUPPORT_CORRIDOR_SCENE_H_
