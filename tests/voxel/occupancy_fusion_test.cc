// Occupancy fusion of a placed submap into the merged map, checked voxel by
// voxel against the rule worked out from the two inputs alone.
#include "voxel/occupancy_fusion.h"

#include <gtest/gtest.h>
#include <octomap/OcTree.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <random>
#include <string>
#include <vector>

#include "voxel/octree_leaves.h"
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

// The cap drops the big open cubes, not the small leaves near surfaces: free
// leaves are spent smallest first, whatever the tree's order.
TEST(OccupancyFusionTest, TheCapLeavesOutTheLargestFreeLeavesFirst) {
  octomap::OcTree a(kTreeRes), b(kTreeRes);
  Set(&a, 0, S::kOccupied);
  for (int x = 16; x < 24; ++x)  // an aligned 8^3 block: one leaf of 512 voxels
    for (int y = 0; y < 8; ++y)
      for (int z = 0; z < 8; ++z) Set(&b, x, S::kFree, y, z);
  for (int x = 40; x < 46; x += 2) Set(&b, x, S::kFree);  // three single voxels beyond it
  b.prune();
  for (const int threads : {1, 3}) {
    FusionParams params;
    // Room for the big leaf alone; spent smallest first, the three singles
    // come first and the big leaf no longer fits.
    params.max_free_voxels = 513;
    params.threads = threads;
    FusionStats stats;
    auto merged = FuseTrees(a, b, Eigen::Isometry3d::Identity(), params, &stats);
    ASSERT_TRUE(merged.ok());
    EXPECT_EQ(stats.free_voxels_skipped, 512u) << threads;
    EXPECT_EQ(stats.free_written, 3u) << threads;
    EXPECT_EQ(StateOf(**merged, 17, 1, 1), S::kUnknown) << threads;
    EXPECT_EQ(StateOf(**merged, 42), S::kFree) << threads;
  }
}

// Morton codes of the voxels of [x0, x0 + n)^3 (keys as Key()).
std::vector<std::uint64_t> CubeCodes(int x0, int n) {
  std::vector<std::uint64_t> codes;
  for (int x = x0; x < x0 + n; ++x)
    for (int y = x0; y < x0 + n; ++y)
      for (int z = x0; z < x0 + n; ++z) codes.push_back(internal::MortonCode(Key(x, y, z)));
  return codes;
}

// What the tree knows is kept: an occupied voxel, a pruned free 4^3 leaf
// and the voxels under a pruned leaf are left as they are; the rest of the
// cube is written (as whole nodes), in any order and with repeats.
TEST(OccupancyFusionTest, WriteUnknownVoxelsKeepsWhatTheTreeKnows) {
  octomap::OcTree tree(kTreeRes);
  SetFreeBlock(&tree);  // [0, 4)^3, one leaf after prune
  Set(&tree, 5, S::kOccupied, 6, 7);
  Set(&tree, 16, S::kOccupied);  // outside the cube
  tree.prune();
  std::vector<std::uint64_t> codes = CubeCodes(0, 8);
  std::reverse(codes.begin(), codes.end());
  codes.push_back(codes.front());  // a repeat
  const float occupied = tree.getClampingThresMaxLog();
  EXPECT_EQ(internal::WriteUnknownVoxels(&codes, occupied, &tree), 512u - 64u - 1u);
  tree.updateInnerOccupancy();
  for (int x = 0; x < 8; ++x)
    for (int y = 0; y < 8; ++y)
      for (int z = 0; z < 8; ++z) {
        const bool kept_free = x < 4 && y < 4 && z < 4;
        EXPECT_EQ(StateOf(tree, x, y, z), kept_free ? S::kFree : S::kOccupied) << x << y << z;
      }
  EXPECT_EQ(StateOf(tree, 8, 8, 8), S::kUnknown);
  // Inside a leaf, or the leaf itself: nothing to write.
  for (int n : {2, 4}) {
    std::vector<std::uint64_t> inside = CubeCodes(0, n);
    EXPECT_EQ(internal::WriteUnknownVoxels(&inside, occupied, &tree), 0u);
    EXPECT_EQ(StateOf(tree, 1, 1, 1), S::kFree);
  }
  // An empty tree takes every voxel: a 2^3 node less one voxel, with a
  // repeat (eight codes that are not a whole node), and a 4^3 node.
  octomap::OcTree empty(kTreeRes);
  std::vector<std::uint64_t> seven = CubeCodes(-8, 2);
  std::sort(seven.begin(), seven.end());
  seven[3] = seven[5];  // child 3 of the node: x and y + 1
  EXPECT_EQ(internal::WriteUnknownVoxels(&seven, occupied, &empty), 7u);
  EXPECT_EQ(StateOf(empty, -7, -7, -8), S::kUnknown);
  EXPECT_EQ(StateOf(empty, -8, -7, -7), S::kOccupied);
  std::vector<std::uint64_t> all = CubeCodes(-4, 4);
  EXPECT_EQ(internal::WriteUnknownVoxels(&all, occupied, &empty), 64u);
  EXPECT_EQ(StateOf(empty, -1, -2, -3), S::kOccupied);
  EXPECT_EQ(StateOf(empty, 0, 0, 0), S::kUnknown);
}

// b's free cube [0, 4)^3 beside a's free [0, 2)^3 leaf: written as seven
// 2^3 nodes, it makes one free 4^3 leaf with a's. OcTree::prune would stop
// at the finest level, where it finds nothing to collapse.
TEST(OccupancyFusionTest, FreeSpaceBesideTheMergedMapPrunesIntoOneLeaf) {
  octomap::OcTree a(kTreeRes), b(kTreeRes);
  for (int x = 0; x < 2; ++x)
    for (int y = 0; y < 2; ++y)
      for (int z = 0; z < 2; ++z) Set(&a, x, S::kFree, y, z);
  SetFreeBlock(&b);
  a.prune();
  b.prune();
  FusionStats stats;
  auto merged = FuseAtIdentity(a, b, &stats);
  ASSERT_TRUE(merged.ok()) << merged.status().ToString();
  EXPECT_EQ(stats.free_written, 56u);
  int leaves = 0;
  ForEachLeaf(**merged,
              [&](const octomap::OcTreeNode& node, const octomap::OcTreeKey&, unsigned d) {
                ++leaves;
                EXPECT_EQ(d, (*merged)->getTreeDepth() - 2);
                EXPECT_FALSE((*merged)->isNodeOccupied(node));
              });
  EXPECT_EQ(leaves, 1);
}

// A random submap of voxels in [-16, 16)^3: free boxes (some of them
// aligned 8^3 cubes, which prune to one leaf) and occupied voxels, pruned.
octomap::OcTree RandomSubmap(std::mt19937* random) {
  octomap::OcTree tree(kTreeRes);
  std::uniform_int_distribution<int> at(-16, 15), edge(1, 10), cube(-2, 1);
  for (int k = 0; k < 6; ++k) {
    const bool aligned = k < 2;
    const int x0 = aligned ? 8 * cube(*random) : at(*random);
    const int y0 = aligned ? 8 * cube(*random) : at(*random);
    const int z0 = aligned ? 8 * cube(*random) : at(*random);
    const int ex = aligned ? 8 : edge(*random), ey = aligned ? 8 : edge(*random),
              ez = aligned ? 8 : edge(*random);
    for (int x = x0; x < x0 + ex; ++x)
      for (int y = y0; y < y0 + ey; ++y)
        for (int z = z0; z < z0 + ez; ++z) Set(&tree, x, S::kFree, y, z);
  }
  for (int k = 0; k < 60; ++k) Set(&tree, at(*random), S::kOccupied, at(*random), at(*random));
  tree.updateInnerOccupancy();
  tree.prune();
  return tree;
}

// The box of a tree's leaves (voxel faces, metres, the tree's frame).
Eigen::AlignedBox3d LeafBox(const octomap::OcTree& tree) {
  Eigen::AlignedBox3d box;
  ForEachLeaf(tree, [&](const octomap::OcTreeNode&, const octomap::OcTreeKey& key, unsigned d) {
    const double half = 0.5 * tree.getNodeSize(d);
    const octomap::point3d c = tree.keyToCoord(key, d);
    box.extend(Eigen::Vector3d(c.x() - half, c.y() - half, c.z() - half));
    box.extend(Eigen::Vector3d(c.x() + half, c.y() + half, c.z() + half));
  });
  return box;
}

// Whether a node below the root still has eight leaf children of one value.
bool HasCollapsibleNode(const octomap::OcTree& tree, const octomap::OcTreeNode* node, bool root) {
  if (!tree.nodeHasChildren(node)) return false;
  if (!root && tree.isNodeCollapsible(node)) return true;
  for (unsigned i = 0; i < 8; ++i) {
    if (tree.nodeChildExists(node, i) &&
        HasCollapsibleNode(tree, tree.getNodeChild(node, i), false))
      return true;
  }
  return false;
}

// Every voxel of the merged map against the rule (docs/algorithms.md B.6),
// worked out from a and b alone: occupied in either -> occupied; free in
// both -> free; free in one and unknown in the other -> unknown inside the
// overlap (a's leaf box and b's, each in its own frame), free outside it.
// Random submaps with free cubes that fuse into whole nodes, turned by a
// random yaw or moved by whole cubes. The merged tree must also be pruned
// as far as it goes (OcTree::prune's own result on per-voxel writes).
TEST(OccupancyFusionTest, EveryVoxelFollowsTheRuleOnRandomSubmaps) {
  for (unsigned seed = 1; seed <= 6; ++seed) {
    std::mt19937 random(seed);
    const octomap::OcTree a = RandomSubmap(&random), b = RandomSubmap(&random);
    std::uniform_real_distribution<double> angle(-M_PI, M_PI);
    // Odd seeds: a yaw and a shift of a fraction of a voxel; even seeds: a
    // shift by whole 8-voxel cubes, so b's cubes land on whole nodes.
    Eigen::Isometry3d T_a_b = seed % 2 == 1
                                  ? Eigen::Translation3d(0.23, -0.61, 0.07) *
                                        Eigen::AngleAxisd(angle(random), Eigen::Vector3d::UnitZ())
                                  : Eigen::Isometry3d(Eigen::Translation3d(1.6, -0.8, 0.8));
    FusionStats stats;
    auto merged = FuseTrees(a, b, T_a_b, FusionParams{}, &stats);
    ASSERT_TRUE(merged.ok()) << merged.status().ToString();
    const Eigen::AlignedBox3d box_a = LeafBox(a), box_b = LeafBox(b);
    const Eigen::Isometry3d T_b_a = T_a_b.inverse();
    int checked = 0, near_a_face = 0, free_from_b = 0;
    for (int x = -48; x < 48; ++x) {
      for (int y = -48; y < 48; ++y) {
        for (int z = -40; z < 40; ++z) {
          const Eigen::Vector3d c = (Eigen::Vector3d(x, y, z).array() + 0.5) * kTreeRes;
          const Eigen::Vector3d q = T_b_a * c;
          // Float leaf corners decide centres that map within 1e-4 m of one
          // of b's voxel faces; those are not checked.
          const Eigen::Vector3d in_voxel = q / kTreeRes - (q / kTreeRes).array().floor().matrix();
          if ((in_voxel.array() < 1e-3).any() || (in_voxel.array() > 1 - 1e-3).any()) {
            ++near_a_face;
            continue;
          }
          const S in_a = StateOf(a, x, y, z);
          const octomap::OcTreeNode* node_b = b.search(q.x(), q.y(), q.z());
          const S in_b = node_b == nullptr ? S::kUnknown
                                           : (b.isNodeOccupied(node_b) ? S::kOccupied : S::kFree);
          S expected = S::kUnknown;
          if (in_a == S::kOccupied || in_b == S::kOccupied) {
            expected = S::kOccupied;
          } else if (in_a == S::kFree && in_b == S::kFree) {
            expected = S::kFree;
          } else if (in_a == S::kFree) {
            expected = box_b.contains(q) ? S::kUnknown : S::kFree;
          } else if (in_b == S::kFree) {
            expected = box_a.contains(c) ? S::kUnknown : S::kFree;
            free_from_b += expected == S::kFree ? 1 : 0;
          }
          ASSERT_EQ(StateOf(**merged, x, y, z), expected)
              << "seed " << seed << " voxel " << x << " " << y << " " << z;
          ++checked;
        }
      }
    }
    EXPECT_GT(checked, 600000);
    EXPECT_GT(free_from_b, 100) << "seed " << seed;  // b's free space outside a's box was written
    EXPECT_GE(stats.free_written, static_cast<std::uint64_t>(free_from_b)) << "seed " << seed;
    EXPECT_LE(stats.free_written, static_cast<std::uint64_t>(free_from_b + near_a_face));
    EXPECT_FALSE(HasCollapsibleNode(**merged, (*merged)->getRoot(), true)) << "seed " << seed;
  }
}

// The reading on threads changes nothing: the same tree (its .bt bytes) and
// the same counts on 1 and 3 threads, also where the free-voxel cap leaves
// some of each map's free leaves out (which ones hangs on the order the cap
// is spent in).
TEST(OccupancyFusionTest, FusesTheSameTreeOnOneAndThreeThreads) {
  for (unsigned seed = 1; seed <= 4; ++seed) {
    std::mt19937 random(seed);
    const octomap::OcTree a = RandomSubmap(&random), b = RandomSubmap(&random);
    const Eigen::Isometry3d T_a_b = Eigen::Translation3d(0.23, -0.61, 0.07) *
                                    Eigen::AngleAxisd(0.3 * seed, Eigen::Vector3d::UnitZ());
    for (const std::uint64_t cap : {std::uint64_t{8'000'000}, std::uint64_t{1500}}) {
      FusionParams one;
      one.max_free_voxels = cap;
      FusionParams three = one;
      three.threads = 3;
      FusionStats stats_one, stats_three;
      auto merged_one = FuseTrees(a, b, T_a_b, one, &stats_one);
      auto merged_three = FuseTrees(a, b, T_a_b, three, &stats_three);
      ASSERT_TRUE(merged_one.ok() && merged_three.ok());
      const std::string at = "seed " + std::to_string(seed) + " cap " + std::to_string(cap);
      EXPECT_EQ(*WriteBinaryOctree(**merged_one), *WriteBinaryOctree(**merged_three)) << at;
      EXPECT_EQ(stats_one.occupied_written, stats_three.occupied_written) << at;
      EXPECT_EQ(stats_one.free_written, stats_three.free_written) << at;
      EXPECT_EQ(stats_one.free_cleared, stats_three.free_cleared) << at;
      EXPECT_EQ(stats_one.free_voxels_skipped, stats_three.free_voxels_skipped) << at;
      if (cap < 8'000'000) {
        EXPECT_GT(stats_one.free_voxels_skipped, 0u) << at;  // the cap bit
      }
      EXPECT_GT(stats_one.free_cleared, 0u) << at;
    }
  }
}

TEST(OccupancyFusionTest, ValidateRefusesAThreadCountOutOfRange) {
  FusionParams params;
  params.threads = 0;
  EXPECT_EQ(params.Validate().code(), StatusCode::kInvalidArgument);
  params.threads = 257;
  EXPECT_EQ(params.Validate().code(), StatusCode::kInvalidArgument);
  params.threads = 256;
  EXPECT_TRUE(params.Validate().ok());
}

}  // namespace
}  // namespace mapd::voxel
