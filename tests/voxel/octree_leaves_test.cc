// ForEachLeaf against OctoMap's own leaf iterator: same leaves, keys, depths
// and order.
#include "voxel/octree_leaves.h"

#include <gtest/gtest.h>
#include <octomap/OcTree.h>

#include <random>
#include <tuple>
#include <vector>

namespace mapd::voxel {
namespace {

using LeafVisit = std::tuple<const octomap::OcTreeNode*, octomap::OcTreeKey, unsigned>;

std::vector<LeafVisit> IteratorLeaves(const octomap::OcTree& tree) {
  std::vector<LeafVisit> leaves;
  for (auto it = tree.begin_leafs(), end = tree.end_leafs(); it != end; ++it) {
    leaves.emplace_back(&*it, it.getKey(), it.getDepth());
  }
  return leaves;
}

std::vector<LeafVisit> RecursionLeaves(const octomap::OcTree& tree) {
  std::vector<LeafVisit> leaves;
  ForEachLeaf(tree, [&](const octomap::OcTreeNode& node, const octomap::OcTreeKey& key,
                        unsigned depth) { leaves.emplace_back(&node, key, depth); });
  return leaves;
}

TEST(OctreeLeavesTest, SameLeavesKeysDepthsAndOrderAsTheLeafIterator) {
  octomap::OcTree tree(0.1);
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> near(-3.0F, 3.0F), far(-3000.0F, 3000.0F);
  for (int i = 0; i < 4000; ++i) {
    // Mostly a dense cluster about the origin (all eight octants), some far
    // away (other branches near the root), both states.
    std::uniform_real_distribution<float>& d = i % 10 == 0 ? far : near;
    tree.updateNode(octomap::point3d(d(rng), d(rng), d(rng)), i % 3 != 0);
  }
  // A free block that prunes to one leaf of edge 8 voxels (depth 13).
  for (int x = 0; x < 8; ++x)
    for (int y = 0; y < 8; ++y)
      for (int z = 0; z < 8; ++z)
        tree.setNodeValue(octomap::point3d(10.05F + 0.1F * x, 10.05F + 0.1F * y, 0.05F + 0.1F * z),
                          -2.0F);
  tree.updateInnerOccupancy();
  tree.prune();
  const std::vector<LeafVisit> expected = IteratorLeaves(tree);
  ASSERT_GT(expected.size(), 3000u);
  bool coarse_leaf = false;
  for (const auto& leaf : expected) coarse_leaf = coarse_leaf || std::get<2>(leaf) < 16;
  EXPECT_TRUE(coarse_leaf);
  EXPECT_EQ(RecursionLeaves(tree), expected);
}

TEST(OctreeLeavesTest, EmptyTreeHasNoLeaves) {
  const octomap::OcTree tree(0.05);
  EXPECT_TRUE(RecursionLeaves(tree).empty());
}

}  // namespace
}  // namespace mapd::voxel
