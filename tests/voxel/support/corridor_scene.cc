#include "voxel/support/corridor_scene.h"

#include <gtest/gtest.h>
#include <octomap/OcTree.h>

#include "voxel/octree_reader.h"

namespace mapd::testing {

VoxelScene Corridor() {
  VoxelScene scene;
  scene.boxes = {
      {Eigen::Vector3d(0.05, 0.05, 0.05), Eigen::Vector3d(12.05, 3.05, 2.55), true},
      // A only: a large cupboard before B's strip starts.
      {Eigen::Vector3d(2.05, 1.25, 0.05), Eigen::Vector3d(3.05, 3.05, 2.05), false},
      // Shared: a free-standing cabinet off the corridor's axis.
      {Eigen::Vector3d(5.05, 0.65, 0.05), Eigen::Vector3d(5.85, 1.35, 1.65), false},
      // B only: a large cupboard after A's strip ends.
      {Eigen::Vector3d(9.05, 0.05, 0.05), Eigen::Vector3d(10.05, 1.85, 2.05), false},
  };
  return scene;
}

Eigen::AlignedBox3d CorridorCropA() {
  return Eigen::AlignedBox3d(Eigen::Vector3d(-0.5, -0.5, -0.5), Eigen::Vector3d(8.0, 3.6, 3.0));
}

Eigen::AlignedBox3d CorridorCropB() {
  return Eigen::AlignedBox3d(Eigen::Vector3d(4.0, -0.5, -0.5), Eigen::Vector3d(12.5, 3.6, 3.0));
}

VoxelScene EmptyRoom() {
  VoxelScene scene;
  scene.boxes = {{Eigen::Vector3d(0.05, 0.05, 0.05), Eigen::Vector3d(6.05, 3.05, 2.55), true}};
  return scene;
}

voxel::VoxelGrid GridOf(const std::string& bt_bytes) {
  auto tree = voxel::ReadOctree(bt_bytes);
  EXPECT_TRUE(tree.ok()) << tree.status().ToString();
  if (!tree.ok()) return {};
  auto grid = voxel::VoxelGrid::FromOcTree(**tree);
  EXPECT_TRUE(grid.ok()) << grid.status().ToString();
  return grid.ok() ? std::move(grid).value() : voxel::VoxelGrid{};
}

}  // namespace mapd::testing
