// The operator's voxel edits (voxel/map_edit.h; mapctl submap crop |
// transform): checked voxel for voxel against key arithmetic.
#include "voxel/map_edit.h"

#include <gtest/gtest.h>
#include <octomap/OcTree.h>

#include <Eigen/Geometry>
#include <cmath>
#include <sstream>
#include <string>

#include "voxel/support/lattice_copy.h"
#include "voxel/support/voxel_scene.h"

namespace mapd::voxel {
namespace {

using testing::StatesOf;
using testing::VoxelStates;

std::string Room() {
  return testing::RasteriseSubmap(testing::FurnishedRoom(), testing::RoomCropX(-0.5, 9.5),
                                  Eigen::Isometry3d::Identity(), testing::kRoomResolutionM);
}

// A map whose free space is one leaf of 16^3 voxels (pruned), with one
// occupied voxel beside it: a box through the leaf must split it.
std::string BigFreeLeaf(double resolution_m) {
  octomap::OcTree tree(resolution_m);
  for (int x = 0; x < 16; ++x)
    for (int y = 0; y < 16; ++y)
      for (int z = 0; z < 16; ++z) {
        tree.setNodeValue(octomap::OcTreeKey(32768 + x, 32768 + y, 32768 + z),
                          tree.getClampingThresMinLog(), true);
      }
  tree.setNodeValue(octomap::OcTreeKey(32768 + 16, 32768, 32768), tree.getClampingThresMaxLog(),
                    true);
  tree.updateInnerOccupancy();
  tree.prune();
  std::ostringstream out;
  tree.writeBinary(out);
  return out.str();
}

// The voxels of `states` whose centres lie in `box` (metres).
VoxelStates Inside(const VoxelStates& states, double resolution_m, const Eigen::AlignedBox3d& box) {
  VoxelStates out;
  for (const auto& [packed, occupied] : states) {
    const Eigen::Vector3d centre(((packed >> 32) & 0xffff), ((packed >> 16) & 0xffff),
                                 packed & 0xffff);
    const Eigen::Vector3d c = (centre - Eigen::Vector3d::Constant(32768 - 0.5)) * resolution_m;
    if (box.contains(c)) out.emplace(packed, occupied);
  }
  return out;
}

std::string Bt(const octomap::OcTree& tree) {
  StatusOr<std::string> bytes = WriteBinaryOctree(tree);
  EXPECT_TRUE(bytes.ok());
  return bytes.ok() ? *bytes : std::string();
}

size_t Occupied(const VoxelStates& states) {
  size_t n = 0;
  for (const auto& entry : states) n += entry.second ? 1 : 0;
  return n;
}

TEST(CropMapTest, KeepsExactlyTheVoxelsWhoseCentresLieInTheBox) {
  const std::string bt = Room();
  StatusOr<OcTreePtr> tree = ReadOctree(bt);
  ASSERT_TRUE(tree.ok());
  // Faces between voxel centres and through them (0.1 m voxels: centres at
  // 0.05 + k 0.1): both kinds of edge.
  const Eigen::AlignedBox3d box(Eigen::Vector3d(1.02, -0.5, 0.25),
                                Eigen::Vector3d(4.35, 2.11, 1.9));
  StatusOr<OcTreePtr> cropped = CropMap(**tree, box);
  ASSERT_TRUE(cropped.ok()) << cropped.status().ToString();
  const VoxelStates expected = Inside(StatesOf(bt), testing::kRoomResolutionM, box);
  ASSERT_GT(Occupied(expected), 500u);
  ASSERT_GT(expected.size() - Occupied(expected), 10000u);  // free space too
  EXPECT_EQ(testing::DescribeDifference(StatesOf(Bt(**cropped)), expected), "");
}

TEST(CropMapTest, SplitsALargeLeafTheBoxCutsThrough) {
  const std::string bt = BigFreeLeaf(0.1);
  StatusOr<OcTreePtr> tree = ReadOctree(bt);
  ASSERT_TRUE(tree.ok());
  ASSERT_LT((*tree)->size(), 40u);  // the 4096 free voxels are one leaf
  const Eigen::AlignedBox3d box(Eigen::Vector3d(0.31, 0.0, -1.0), Eigen::Vector3d(0.74, 0.5, 0.22));
  StatusOr<OcTreePtr> cropped = CropMap(**tree, box);
  ASSERT_TRUE(cropped.ok()) << cropped.status().ToString();
  const VoxelStates expected = Inside(StatesOf(bt), 0.1, box);
  EXPECT_EQ(expected.size(), 4u * 5u * 2u);  // centres x 0.35..0.65, y 0.05..0.45, z 0.05, 0.15
  EXPECT_EQ(testing::DescribeDifference(StatesOf(Bt(**cropped)), expected), "");

  MapEditLimits small;
  small.max_output_nodes = 20;
  const StatusOr<OcTreePtr> refused = CropMap(**tree, box, small);
  EXPECT_EQ(refused.status().code(), StatusCode::kResourceExhausted);
}

TEST(CropMapTest, RefusesABoxThatHoldsNothingOrIsNoBox) {
  StatusOr<OcTreePtr> tree = ReadOctree(Room());
  ASSERT_TRUE(tree.ok());
  const StatusOr<OcTreePtr> far =
      CropMap(**tree, Eigen::AlignedBox3d(Eigen::Vector3d(50, 50, 0), Eigen::Vector3d(60, 60, 2)));
  EXPECT_EQ(far.status().code(), StatusCode::kFailedPrecondition);
  EXPECT_NE(far.status().message().find("occupied voxels lie within"), std::string::npos)
      << far.status().message();
  const StatusOr<OcTreePtr> inverted =
      CropMap(**tree, Eigen::AlignedBox3d(Eigen::Vector3d(2, 0, 0), Eigen::Vector3d(1, 1, 1)));
  EXPECT_EQ(inverted.status().code(), StatusCode::kInvalidArgument);
  const StatusOr<OcTreePtr> nan =
      CropMap(**tree, Eigen::AlignedBox3d(Eigen::Vector3d(NAN, 0, 0), Eigen::Vector3d(1, 1, 1)));
  EXPECT_EQ(nan.status().code(), StatusCode::kInvalidArgument);
}

TEST(TransformMapTest, AQuarterTurnAndWholeVoxelsMoveEveryVoxelExactly) {
  const std::string bt = Room();
  StatusOr<OcTreePtr> tree = ReadOctree(bt);
  ASSERT_TRUE(tree.ok());
  testing::LatticeMove move;
  move.rotation << 0, -1, 0, 1, 0, 0, 0, 0, 1;
  move.shift_voxels = Eigen::Vector3i(7, -3, 2);
  StatusOr<OcTreePtr> moved = TransformMap(**tree, move.Transform(testing::kRoomResolutionM));
  ASSERT_TRUE(moved.ok()) << moved.status().ToString();
  EXPECT_EQ(testing::DescribeDifference(StatesOf(Bt(**moved)),
                                        StatesOf(testing::MoveByLattice(bt, move))),
            "");
}

TEST(TransformMapTest, AnyPoseMovesTheSurfacesWithoutHoles) {
  const std::string bt = Room();
  StatusOr<OcTreePtr> tree = ReadOctree(bt);
  ASSERT_TRUE(tree.ok());
  const Eigen::Isometry3d T = testing::Pose(33, 4, -3, Eigen::Vector3d(0.43, -1.27, 0.31));
  StatusOr<OcTreePtr> moved = TransformMap(**tree, T);
  ASSERT_TRUE(moved.ok()) << moved.status().ToString();
  // Every occupied voxel of the input, moved, lands on or next to an occupied
  // voxel of the output (nearest-neighbour resampling: no holes).
  const double res = testing::kRoomResolutionM;
  size_t input = 0, missed = 0;
  for (octomap::OcTree::leaf_iterator it = (*tree)->begin_leafs(); it != (*tree)->end_leafs();
       ++it) {
    if (!(*tree)->isNodeOccupied(*it) || it.getDepth() != (*tree)->getTreeDepth()) continue;
    ++input;
    const octomap::point3d c = it.getCoordinate();
    const Eigen::Vector3d p = T * Eigen::Vector3d(c.x(), c.y(), c.z());
    bool near = false;
    for (int dx = -1; dx <= 1 && !near; ++dx)
      for (int dy = -1; dy <= 1 && !near; ++dy)
        for (int dz = -1; dz <= 1 && !near; ++dz) {
          const octomap::OcTreeNode* node =
              (*moved)->search(p.x() + dx * res, p.y() + dy * res, p.z() + dz * res);
          near = node != nullptr && (*moved)->isNodeOccupied(node);
        }
    missed += near ? 0 : 1;
  }
  ASSERT_GT(input, 1000u);
  EXPECT_EQ(missed, 0u) << "of " << input;
}

TEST(TransformMapTest, RefusesWhatIsNotARigidMoveOrLeavesTheKeyRange) {
  StatusOr<OcTreePtr> tree = ReadOctree(Room());
  ASSERT_TRUE(tree.ok());
  Eigen::Isometry3d scaled = Eigen::Isometry3d::Identity();
  scaled.linear() *= 2.0;
  EXPECT_EQ(TransformMap(**tree, scaled).status().code(), StatusCode::kInvalidArgument);
  Eigen::Isometry3d nan = Eigen::Isometry3d::Identity();
  nan.translation().x() = NAN;
  EXPECT_EQ(TransformMap(**tree, nan).status().code(), StatusCode::kInvalidArgument);
  Eigen::Isometry3d far = Eigen::Isometry3d::Identity();
  far.translation().x() = 5000.0;  // keys reach +-3276.8 m at 0.1 m
  const StatusOr<OcTreePtr> out = TransformMap(**tree, far);
  EXPECT_EQ(out.status().code(), StatusCode::kFailedPrecondition);
  EXPECT_NE(out.status().message().find("key range"), std::string::npos);
  MapEditLimits small;
  small.max_box_voxels = 1000;
  EXPECT_EQ(TransformMap(**tree, Eigen::Isometry3d::Identity(), small).status().code(),
            StatusCode::kResourceExhausted);
}

}  // namespace
}  // namespace mapd::voxel
