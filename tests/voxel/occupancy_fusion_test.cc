#include "voxel/occupancy_fusion.h"

#include <gtest/gtest.h>
#include <octomap/OcTree.h>

#include <Eigen/Geometry>
#include <string>
#include <vector>

#include "voxel/octree_reader.h"

namespace mapd::voxel {
namespace {

constexpr double kTreeRes = 0.1;  // metres

enum class S { kUnknown, kFree, kOccupied };

// Voxel (x, 0, 0) of a tree at kTreeRes, keys as in VoxelGrid (OctoMap's - 32768).
octomap::OcTreeKey Key(int x, int y = 0, int z = 0) {
  return octomap::OcTreeKey(static_cast<octomap::key_type>(x + 32768),
                            static_cast<octomap::key_type>(y + 32768),
                            static_cast<octomap::key_type>(z + 32768));
}

void Set(octomap::OcTree* tree, int x, S state, int y = 0, int z = 0) {
  if (state == S::kUnknown) return;
  tree->setNodeValue(Key(x, y, z), state == S::kOccupied ? tree->getClampingThresMaxLog()
                                                         : tree->getClampingThresMinLog());
}

S StateOf(const octomap::OcTree& tree, int x, int y = 0, int z = 0) {
  const octomap::OcTreeNode* node = tree.search(Key(x, y, z));
  if (node == nullptr) return S::kUnknown;
  return tree.isNodeOccupied(node) ? S::kOccupied : S::kFree;
}

// A pruned free block of 4x4x4 voxels at the origin (one leaf of level 2).
void SetFreeBlock(octomap::OcTree* tree) {
  for (int x = 0; x < 4; ++x)
    for (int y = 0; y < 4; ++y)
      for (int z = 0; z < 4; ++z) Set(tree, x, S::kFree, y, z);
}

// a with b (placed by T_a_b) fused in, or the first error.
StatusOr<OcTreePtr> FuseTrees(const octomap::OcTree& a, const octomap::OcTree& b,
                              const Eigen::Isometry3d& T_a_b, const FusionParams& params,
                              FusionStats* stats) {
  auto merged = StartMergedMap(a, kTreeRes, params);
  if (!merged.ok()) return merged.status();
  MAPD_RETURN_IF_ERROR(FuseInto(b, T_a_b, params, merged->get(), stats));
  return merged;
}

StatusOr<OcTreePtr> FuseAtIdentity(const octomap::OcTree& a, const octomap::OcTree& b,
                                   FusionStats* stats) {
  return FuseTrees(a, b, Eigen::Isometry3d::Identity(), FusionParams{}, stats);
}

// The tree written as a .bt and read back (what a client gets).
StatusOr<OcTreePtr> Reread(const octomap::OcTree& tree) {
  auto bytes = WriteBinaryOctree(tree);
  if (!bytes.ok()) return bytes.status();
  return ReadOctree(*bytes);
}

// A's voxels x in [0, 10], B's in [5, 14] (a row along x): the overlap region
// is x in [5, 10]. B is given in its own frame, where x' = x - 5, so T_a_b is
// a translation of +0.5 m along x.
struct Row {
  octomap::OcTree a{kTreeRes}, b{kTreeRes};
  Eigen::Isometry3d T_a_b = Eigen::Isometry3d(Eigen::Translation3d(0.5, 0.0, 0.0));
  void A(int x, S s) { Set(&a, x, s); }
  void B(int x, S s) { Set(&b, x - 5, s); }  // x in A's frame
};

// The hand-made cases of docs/algorithms.md B.6 (Eq. 33) along one row.
Row MakeRow() {
  Row row;
  row.A(0, S::kOccupied);  // A's box starts here
  row.A(2, S::kFree);      // outside the overlap: A's own cell
  row.A(5, S::kOccupied);  // occupied + free  -> occupied
  row.B(5, S::kFree);
  row.A(6, S::kFree);  // free + free -> free
  row.B(6, S::kFree);
  row.A(7, S::kFree);       // free + unknown (inside B's box) -> unknown
  row.B(8, S::kFree);       // unknown + free (inside A's box) -> unknown
  row.B(9, S::kOccupied);   // unknown + occupied -> occupied
  row.A(10, S::kOccupied);  // A's box ends here
  row.B(12, S::kFree);      // outside the overlap: B's own cell
  row.B(14, S::kOccupied);  // B's box ends here
  return row;
}

OcTreePtr Fuse(const Row& row, FusionRule rule, FusionStats* stats = nullptr) {
  FusionParams params;
  params.rule = rule;
  auto merged = FuseTrees(row.a, row.b, row.T_a_b, params, stats);
  EXPECT_TRUE(merged.ok()) << merged.status().ToString();
  return std::move(merged).value();
}

TEST(OccupancyFusionTest, OverlapRuleOnHandMadeCases) {
  const Row row = MakeRow();
  FusionStats stats;
  const OcTreePtr merged = Fuse(row, FusionRule::kOverlapRule, &stats);
  EXPECT_EQ(StateOf(*merged, 0), S::kOccupied);
  EXPECT_EQ(StateOf(*merged, 2), S::kFree);      // A only, outside the overlap
  EXPECT_EQ(StateOf(*merged, 5), S::kOccupied);  // occupied + free
  EXPECT_EQ(StateOf(*merged, 6), S::kFree);      // free + free
  EXPECT_EQ(StateOf(*merged, 7), S::kUnknown);   // free + unknown in the overlap
  EXPECT_EQ(StateOf(*merged, 8), S::kUnknown);   // unknown + free in the overlap
  EXPECT_EQ(StateOf(*merged, 9), S::kOccupied);  // unknown + occupied
  EXPECT_EQ(StateOf(*merged, 10), S::kOccupied);
  EXPECT_EQ(StateOf(*merged, 11), S::kUnknown);  // unknown in both
  EXPECT_EQ(StateOf(*merged, 12), S::kFree);     // B only, outside the overlap
  EXPECT_EQ(StateOf(*merged, 14), S::kOccupied);
  EXPECT_EQ(stats.free_cleared, 1u);
  EXPECT_EQ(stats.free_voxels_skipped, 0u);
  EXPECT_EQ(CountOccupiedVoxels(*merged), 5u);
}

TEST(OccupancyFusionTest, LogOddsAddsAndClamps) {
  const Row row = MakeRow();
  const OcTreePtr merged = Fuse(row, FusionRule::kLogOdds);
  // occupied (3.5) + free (-2.0) = 1.5 > 0: occupied.
  EXPECT_EQ(StateOf(*merged, 5), S::kOccupied);
  EXPECT_NEAR(merged->search(Key(5))->getLogOdds(),
              row.a.getClampingThresMaxLog() + row.a.getClampingThresMinLog(), 1e-5);
  EXPECT_EQ(StateOf(*merged, 6), S::kFree);  // clamped at the lower threshold
  EXPECT_NEAR(merged->search(Key(6))->getLogOdds(), row.a.getClampingThresMinLog(), 1e-5);
  EXPECT_EQ(StateOf(*merged, 7), S::kFree);  // free + nothing
  EXPECT_EQ(StateOf(*merged, 8), S::kFree);
  EXPECT_EQ(StateOf(*merged, 9), S::kOccupied);
  EXPECT_EQ(StateOf(*merged, 12), S::kFree);
}

TEST(OccupancyFusionTest, ClearingInsideAPrunedFreeBlockKeepsTheTreeValid) {
  // A: a pruned free 4x4x4 block; B observes its lower half only and knows
  // nothing of the upper half: the upper half becomes unknown (overlap rule),
  // voxel by voxel, through OctoMap's pruned nodes (the path that crashes
  // OctoMap 1.9.7's own deleteNode).
  octomap::OcTree a(kTreeRes), b(kTreeRes);
  SetFreeBlock(&a);
  a.prune();
  for (int x = 0; x < 4; ++x)
    for (int y = 0; y < 4; ++y) {
      Set(&b, x, S::kFree, y, 0);
      Set(&b, x, S::kFree, y, 1);
    }
  Set(&b, 0, S::kOccupied, 0, 3);  // stretches B's box over the whole block
  FusionStats stats;
  auto merged = FuseAtIdentity(a, b, &stats);
  ASSERT_TRUE(merged.ok()) << merged.status().ToString();
  EXPECT_EQ(stats.free_cleared, 31u);  // 32 upper voxels, one of them occupied in B
  for (int x = 0; x < 4; ++x)
    for (int y = 0; y < 4; ++y) {
      EXPECT_EQ(StateOf(**merged, x, y, 1), S::kFree);
      EXPECT_EQ(StateOf(**merged, x, y, 2), S::kUnknown);
    }
  EXPECT_EQ(StateOf(**merged, 0, 0, 3), S::kOccupied);
  auto reread = Reread(**merged);
  ASSERT_TRUE(reread.ok()) << reread.status().ToString();
  EXPECT_EQ(StateOf(**reread, 1, 1, 0), S::kFree);
  EXPECT_EQ(StateOf(**reread, 1, 1, 2), S::kUnknown);
}

TEST(OccupancyFusionTest, AFreeLeafTheSubmapNeverSawIsClearedWhole) {
  // A: a pruned free 4x4x4 block (one leaf) and a free voxel beside it; B's
  // box covers both but B saw only that voxel: the block becomes unknown (at
  // once, as one node), the voxel stays free (free in both).
  octomap::OcTree a(kTreeRes), b(kTreeRes);
  SetFreeBlock(&a);
  Set(&a, 5, S::kFree, 0, 0);
  a.prune();
  Set(&b, 5, S::kFree, 0, 0);
  Set(&b, -1, S::kOccupied, -1, -1);  // B's box holds the block
  Set(&b, 6, S::kOccupied, 5, 5);
  FusionStats stats;
  auto merged = FuseAtIdentity(a, b, &stats);
  ASSERT_TRUE(merged.ok()) << merged.status().ToString();
  EXPECT_EQ(stats.free_cleared, 64u);
  for (int x = 0; x < 4; ++x)
    for (int y = 0; y < 4; ++y)
      for (int z = 0; z < 4; ++z) EXPECT_EQ(StateOf(**merged, x, y, z), S::kUnknown);
  EXPECT_EQ(StateOf(**merged, 5, 0, 0), S::kFree);
  EXPECT_EQ(StateOf(**merged, -1, -1, -1), S::kOccupied);
  auto reread = Reread(**merged);
  ASSERT_TRUE(reread.ok()) << reread.status().ToString();
  EXPECT_EQ(StateOf(**reread, 2, 2, 2), S::kUnknown);
  EXPECT_EQ(StateOf(**reread, 5, 0, 0), S::kFree);
}

TEST(OccupancyFusionTest, RotatedSubmapLandsOnTheRightVoxels) {
  octomap::OcTree a(kTreeRes), b(kTreeRes);
  Set(&a, 0, S::kOccupied);
  Set(&b, 3, S::kOccupied);  // (0.35, 0.05, 0.05) in B
  // 90 deg about z through B's origin: (x, y) -> (-y, x); voxel 3 -> centre (-0.05, 0.35).
  Eigen::Isometry3d T_a_b(Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitZ()));
  FusionParams params;
  auto merged = StartMergedMap(a, kTreeRes, params);
  ASSERT_TRUE(merged.ok());
  ASSERT_TRUE(FuseInto(b, T_a_b, params, merged->get()).ok());
  EXPECT_EQ(StateOf(**merged, -1, 3), S::kOccupied);
  EXPECT_EQ(CountOccupiedVoxels(**merged), 2u);
}

TEST(OccupancyFusionTest, ResamplesACoarserMapToTheFinerGrid) {
  octomap::OcTree coarse(2 * kTreeRes);
  coarse.setNodeValue(coarse.coordToKey(octomap::point3d(0.1f, 0.1f, 0.1f)),
                      coarse.getClampingThresMaxLog());
  FusionParams params;
  auto merged = StartMergedMap(coarse, kTreeRes, params);
  ASSERT_TRUE(merged.ok());
  EXPECT_EQ((*merged)->getResolution(), kTreeRes);
  EXPECT_EQ(CountOccupiedVoxels(**merged), 8u);  // one 0.2 m voxel = eight 0.1 m voxels
  for (int x = 0; x < 2; ++x)
    for (int y = 0; y < 2; ++y)
      for (int z = 0; z < 2; ++z) EXPECT_EQ(StateOf(**merged, x, y, z), S::kOccupied);
  // And fused into a fine map.
  octomap::OcTree fine(kTreeRes);
  Set(&fine, 5, S::kOccupied);
  auto target = StartMergedMap(fine, kTreeRes, params);
  ASSERT_TRUE(target.ok());
  ASSERT_TRUE(FuseInto(coarse, Eigen::Isometry3d::Identity(), params, target->get()).ok());
  EXPECT_EQ(CountOccupiedVoxels(**target), 9u);
}

TEST(OccupancyFusionTest, FreeSpaceBeyondTheCapIsLeftUnknownAndCounted) {
  octomap::OcTree a(kTreeRes), b(kTreeRes);
  Set(&a, 0, S::kOccupied);
  for (int x = 16; x < 24; ++x)  // an aligned 8^3 block
    for (int y = 0; y < 8; ++y)
      for (int z = 0; z < 8; ++z) Set(&b, x, S::kFree, y, z);
  b.prune();  // one free leaf of 512 voxels
  FusionParams params;
  params.max_free_voxels = 100;
  auto merged = StartMergedMap(a, kTreeRes, params);
  ASSERT_TRUE(merged.ok());
  FusionStats stats;
  ASSERT_TRUE(FuseInto(b, Eigen::Isometry3d::Identity(), params, merged->get(), &stats).ok());
  EXPECT_EQ(stats.free_voxels_skipped, 512u);
  EXPECT_EQ(StateOf(**merged, 17, 1, 1), S::kUnknown);
  params.max_free_voxels = 1000;
  stats = FusionStats{};
  ASSERT_TRUE(FuseInto(b, Eigen::Isometry3d::Identity(), params, merged->get(), &stats).ok());
  EXPECT_EQ(stats.free_voxels_skipped, 0u);
  EXPECT_EQ(stats.free_written, 512u);
  EXPECT_EQ(StateOf(**merged, 17, 1, 1), S::kFree);
}

}  // namespace
}  // namespace mapd::voxel
