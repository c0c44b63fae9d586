// VoxelGrid, the dense view of an octree: occupied, free and unknown as OctoMap
// says, coarse leaves expanded, huge ones and bad keys refused.
#include "voxel/voxel_grid.h"

#include <gtest/gtest.h>
#include <octomap/OcTree.h>

namespace mapd::voxel {
namespace {

TEST(VoxelGridTest, MatchesOctoMapOccupiedFreeAndUnknown) {
  octomap::OcTree tree(0.1);
  for (int x = -10; x < 10; ++x)
    for (int y = -5; y < 5; ++y)
      tree.updateNode(octomap::point3d(0.1f * x + 0.05f, 0.1f * y + 0.05f, 0.35f), true);
  // A free 8^3 block that prunes to one coarse leaf.
  for (int x = 0; x < 8; ++x)
    for (int y = 0; y < 8; ++y)
      for (int z = 0; z < 8; ++z)
        for (int i = 0; i < 3; ++i)
          tree.updateNode(
              octomap::point3d(0.1f * x + 0.05f, 0.1f * y + 0.05f, -0.8f + 0.1f * z + 0.05f),
              false);
  tree.prune();
  StatusOr<VoxelGrid> grid = VoxelGrid::FromOcTree(tree);
  ASSERT_TRUE(grid.ok()) << grid.status().ToString();
  EXPECT_EQ(grid->num_occupied(), 200u);
  EXPECT_DOUBLE_EQ(grid->resolution(), 0.1);
  EXPECT_EQ(grid->min_key(), VoxelKey(-10, -5, 3));
  EXPECT_EQ(grid->max_key(), VoxelKey(9, 4, 3));
  EXPECT_NEAR(grid->min_corner().x(), -1.0, 1e-12);
  EXPECT_NEAR(grid->max_corner().z(), 0.4, 1e-12);
  for (int x = -12; x < 12; ++x) {
    for (int y = -7; y < 10; ++y) {
      for (int z = -10; z < 6; ++z) {
        const VoxelKey key(x, y, z);
        const Eigen::Vector3d c = grid->KeyToCentre(key);
        EXPECT_EQ(grid->PointToKey(c), key);
        const octomap::OcTreeNode* node = tree.search(c.x(), c.y(), c.z());
        const VoxelState expected = node == nullptr             ? VoxelState::kUnknown
                                    : tree.isNodeOccupied(node) ? VoxelState::kOccupied
                                                                : VoxelState::kFree;
        ASSERT_EQ(grid->State(key), expected) << key.transpose();
        EXPECT_EQ(grid->IsOccupied(key), expected == VoxelState::kOccupied);
      }
    }
  }
  // The pruned free block comes back as one cube of edge 8 at its minimum key.
  int cubes = 0, free_voxels = 0;
  grid->ForEachFreeCube([&](const VoxelKey& min_key, int edge) {
    ++cubes;
    free_voxels += edge * edge * edge;
    EXPECT_EQ(grid->State(min_key), VoxelState::kFree);
    if (edge == 8) {
      EXPECT_EQ(min_key, VoxelKey(0, 0, -8));
    }
  });
  EXPECT_EQ(cubes, 1);
  EXPECT_EQ(free_voxels, 512);
}

TEST(VoxelGridTest, ExpandsCoarseOccupiedLeavesAndRefusesHugeOnes) {
  octomap::OcTree tree(0.5);
  for (int x = 0; x < 4; ++x)
    for (int y = 0; y < 4; ++y)
      for (int z = 0; z < 4; ++z)
        tree.updateNode(octomap::point3d(0.5f * x + 0.25f, 0.5f * y + 0.25f, 0.5f * z + 0.25f),
                        true);
  tree.toMaxLikelihood();
  tree.prune();
  ASSERT_LT(tree.getNumLeafNodes(), 64u);  // pruned to a coarse leaf
  StatusOr<VoxelGrid> grid = VoxelGrid::FromOcTree(tree);
  ASSERT_TRUE(grid.ok());
  EXPECT_EQ(grid->num_occupied(), 64u);
  EXPECT_TRUE(grid->IsOccupied(VoxelKey(3, 3, 3)));
  EXPECT_FALSE(grid->IsOccupied(VoxelKey(4, 3, 3)));
  VoxelGridLimits limits;
  limits.max_occupied_voxels = 63;
  EXPECT_EQ(VoxelGrid::FromOcTree(tree, limits).status().code(), StatusCode::kResourceExhausted);
}

TEST(VoxelGridTest, FromKeysValidates) {
  EXPECT_FALSE(VoxelGrid::FromKeys(0.0, {}).ok());
  EXPECT_FALSE(VoxelGrid::FromKeys(0.1, {VoxelKey(40000, 0, 0)}).ok());
  StatusOr<VoxelGrid> grid = VoxelGrid::FromKeys(0.1, {VoxelKey(1, 2, 3), VoxelKey(1, 2, 3)},
                                                 {VoxelKey(0, 0, 0), VoxelKey(1, 2, 3)});
  ASSERT_TRUE(grid.ok());
  EXPECT_EQ(grid->num_occupied(), 1u);
  EXPECT_EQ(grid->State(VoxelKey(1, 2, 3)), VoxelState::kOccupied);
  EXPECT_EQ(grid->State(VoxelKey(0, 0, 0)), VoxelState::kFree);
  EXPECT_EQ(grid->State(VoxelKey(0, 0, 1)), VoxelState::kUnknown);
  EXPECT_EQ(grid->State(VoxelKey(-40000, 0, 1)), VoxelState::kUnknown);
  EXPECT_FALSE(grid->IsOccupied(grid->PointToKey(Eigen::Vector3d(1e300, 0, 0))));
  EXPECT_TRUE(VoxelGrid().empty());
}

}  // namespace
}  // namespace mapd::voxel
