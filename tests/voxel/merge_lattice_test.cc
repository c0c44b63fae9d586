// Exact on easy cases (issue 42 item 3; voxel/lattice_pose.h): a map merged
// with an identical copy, or with a copy moved by right angles and whole
// voxels, comes back with exactly that move and a merged map equal to the
// input voxel for voxel (no thickened walls). The same on real maps is in
// merge_real_map_test.cc.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <string>

#include "voxel/lattice_pose.h"
#include "voxel/merge.h"
#include "voxel/support/lattice_copy.h"
#include "voxel/support/voxel_scene.h"

namespace mapd::voxel {
namespace {

using testing::LatticeMove;

constexpr double kPi = 3.14159265358979323846;

std::string WholeRoom() {
  return testing::RasteriseSubmap(testing::FurnishedRoom(), testing::RoomCropX(-0.5, 9.5),
                                  Eigen::Isometry3d::Identity(), testing::kRoomResolutionM);
}

// 90 deg about z, then (7, -3, 2) voxels.
LatticeMove QuarterTurnAndShift() {
  LatticeMove move;
  move.rotation << 0, -1, 0, 1, 0, 0, 0, 0, 1;
  move.shift_voxels = Eigen::Vector3i(7, -3, 2);
  return move;
}

TEST(LatticePoseTest, SnapsANearRotationAndListsTheVoxelCornersAround) {
  const Eigen::Matrix3d quarter =
      Eigen::AngleAxisd(kPi / 2 + 0.003, Eigen::Vector3d::UnitZ()).toRotationMatrix();  // 90.17 deg
  const auto snapped = NearestLatticeRotation(quarter, 0.5 * kPi / 180);
  ASSERT_TRUE(snapped.has_value());
  Eigen::Matrix3d expected;
  expected << 0, -1, 0, 1, 0, 0, 0, 0, 1;
  EXPECT_EQ(*snapped, expected);
  EXPECT_FALSE(NearestLatticeRotation(quarter, 0.1 * kPi / 180).has_value());
  const Eigen::Matrix3d flip = Eigen::AngleAxisd(kPi, Eigen::Vector3d(1, 1, 0).normalized())
                                   .toRotationMatrix();  // swaps x and y, negates z
  ASSERT_TRUE(NearestLatticeRotation(flip, 1e-6).has_value());

  // A translation of (0.3, 1.0, -0.2) voxels at the pivot: the 2 x 1 x 2
  // whole-voxel corners around it.
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.translation() = Eigen::Vector3d(0.3, 1.0, -0.2) * 0.1;
  const auto poses = LatticePosesNear(T, Eigen::Vector3d(1, 2, 3), 0.1, 0.01);
  ASSERT_EQ(poses.size(), 4u);
  for (const Eigen::Isometry3d& pose : poses) {
    const Eigen::Vector3d voxels = pose.translation() / 0.1;
    EXPECT_TRUE(voxels.x() == 0 || voxels.x() == 1) << voxels.transpose();
    EXPECT_EQ(voxels.y(), 1);
    EXPECT_TRUE(voxels.z() == -1 || voxels.z() == 0) << voxels.transpose();
  }
  // Bad input gives no poses rather than a bad one.
  EXPECT_TRUE(LatticePosesNear(T, Eigen::Vector3d(NAN, 0, 0), 0.1, 0.01).empty());
  EXPECT_TRUE(LatticePosesNear(T, Eigen::Vector3d::Zero(), 0.0, 0.01).empty());
}

TEST(MergeLatticeTest, AMapMergedWithItselfIsTheIdentityAndTheSameMap) {
  const std::string room = WholeRoom();
  auto outcome = MergeSubmaps({{1, room}, {2, room}}, MergeParams{});
  ASSERT_TRUE(outcome.ok()) << outcome.status().ToString();
  const Eigen::Isometry3d& T = outcome->alignments[1].T_reference_submap;
  EXPECT_TRUE(T.matrix().isApprox(Eigen::Matrix4d::Identity(), 1e-12)) << T.matrix();
  EXPECT_EQ(outcome->alignments[1].residual_m, 0.0);
  EXPECT_EQ(
      testing::DescribeDifference(testing::StatesOf(outcome->merged_bt), testing::StatesOf(room)),
      "");
}

TEST(MergeLatticeTest, ACopyMovedByALatticePoseGivesThatMoveAndTheSameMap) {
  const std::string room = WholeRoom();
  const LatticeMove move = QuarterTurnAndShift();
  const std::string moved = testing::MoveByLattice(room, move);
  auto outcome = MergeSubmaps({{1, room}, {2, moved}}, MergeParams{});
  ASSERT_TRUE(outcome.ok()) << outcome.status().ToString();
  // T_reference_submap maps the copy back onto the room: the move's inverse.
  const Eigen::Isometry3d expected = move.Transform(testing::kRoomResolutionM).inverse();
  const Eigen::Isometry3d& T = outcome->alignments[1].T_reference_submap;
  EXPECT_TRUE(T.matrix().isApprox(expected.matrix(), 1e-12)) << T.matrix();
  ASSERT_EQ(outcome->pairs.size(), 1u);
  EXPECT_TRUE(outcome->pairs[0].on_lattice);
  // The copy lands on the room voxel for voxel: nothing thickened.
  EXPECT_EQ(
      testing::DescribeDifference(testing::StatesOf(outcome->merged_bt), testing::StatesOf(room)),
      "");
}

TEST(MergeLatticeTest, AMapTurnedOffTheLatticeIsNotSnapped) {
  const std::string a = WholeRoom();
  const std::string b = testing::RasteriseSubmap(
      testing::FurnishedRoom(), testing::RoomCropX(-0.5, 9.5),
      testing::Pose(2.0, 0, 0, Eigen::Vector3d(0.33, -0.21, 0)), testing::kRoomResolutionM);
  auto outcome = MergeSubmaps({{1, a}, {2, b}}, MergeParams{});
  ASSERT_TRUE(outcome.ok()) << outcome.status().ToString();
  ASSERT_EQ(outcome->pairs.size(), 1u);
  EXPECT_FALSE(outcome->pairs[0].on_lattice);
}

}  // namespace
}  // namespace mapd::voxel
