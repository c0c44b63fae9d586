// Gravity alignment: the up vector of a tilted room (and of a ramp floor,
// corrected by the walls), yaw candidates, and the refusal without a floor.
#include "voxel/gravity_alignment.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "voxel/support/corridor_scene.h"
#include "voxel/support/voxel_scene.h"

namespace mapd::voxel {
namespace {

using testing::FurnishedRoom;
using testing::GridOf;
using testing::Pose;
using testing::RasteriseSubmap;

using testing::kRoomResolutionM;

Eigen::AlignedBox3d WholeRoom() {
  return Eigen::AlignedBox3d(Eigen::Vector3d(-1, -1, -1), Eigen::Vector3d(10, 6, 3.5));
}

double AngleDeg(const Eigen::Vector3d& x, const Eigen::Vector3d& y) {
  return std::acos(std::clamp(x.normalized().dot(y.normalized()), -1.0, 1.0)) * 180.0 / M_PI;
}

TEST(GravityAlignmentTest, UpVectorOfATiltedRoom) {
  const Eigen::Isometry3d T_scene_b = Pose(37, 4, -6, Eigen::Vector3d(1.3, -2.1, 0.4));
  const VoxelGrid b =
      GridOf(RasteriseSubmap(FurnishedRoom(), WholeRoom(), T_scene_b, kRoomResolutionM));
  auto frame = EstimateGravityFrame(b, GravityParams{});
  ASSERT_TRUE(frame.ok()) << frame.status().ToString();
  // The scene's +z seen in b's frame.
  const Eigen::Vector3d truth = T_scene_b.linear().transpose() * Eigen::Vector3d::UnitZ();
  EXPECT_LT(AngleDeg(frame->up, truth), 1.0);
  EXPECT_LT(AngleDeg(frame->R_up * frame->up, Eigen::Vector3d::UnitZ()), 1e-6);
  EXPECT_GT(frame->floor_planes, 0);
  EXPECT_GT(frame->wall_planes, 0);
}

TEST(GravityAlignmentTest, YawCandidatesHoldTheTrueYaw) {
  const Eigen::Isometry3d T_a_b = Pose(37, 4, -6, Eigen::Vector3d(1.3, -2.1, 0.4));
  const VoxelGrid a = GridOf(RasteriseSubmap(FurnishedRoom(), WholeRoom(),
                                             Eigen::Isometry3d::Identity(), kRoomResolutionM));
  const VoxelGrid b =
      GridOf(RasteriseSubmap(FurnishedRoom(), WholeRoom(), T_a_b, kRoomResolutionM));
  auto fa = EstimateGravityFrame(a, GravityParams{});
  auto fb = EstimateGravityFrame(b, GravityParams{});
  ASSERT_TRUE(fa.ok() && fb.ok());
  const std::vector<double> yaws = YawCandidates(*fa, *fb, GravityParams{});
  ASSERT_EQ(yaws.size(), 4u);  // two peaks (Manhattan room), each with its twin
  // The true levelled rotation R_a * R_true * R_b^-1 is a turn about z.
  const Eigen::Matrix3d levelled = fa->R_up * T_a_b.linear() * fb->R_up.transpose();
  double best = 180;
  for (double yaw : yaws) {
    const Eigen::Matrix3d candidate = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).matrix();
    best = std::min(best, Eigen::AngleAxisd(candidate.transpose() * levelled).angle() * 180 / M_PI);
  }
  EXPECT_LT(best, 1.0);
  // The 180 deg twin follows each peak.
  EXPECT_NEAR(std::abs(std::remainder(yaws[1] - yaws[0], 2 * M_PI)), M_PI, 1e-9);
}

// A room whose floor is a 4 deg ramp and whose four walls are vertical: the
// floor alone tilts up by 4 deg, the walls pull it back to vertical.
TEST(GravityAlignmentTest, WallsCorrectTheUpOfARampFloor) {
  constexpr int kSide = 60, kHeight = 40;
  const double slope = std::tan(4.0 * M_PI / 180.0);
  std::vector<VoxelKey> keys;
  for (int x = 0; x < kSide; ++x) {
    for (int y = 0; y < kSide; ++y) {
      keys.emplace_back(x, y, static_cast<int>(std::lround(x * slope)));  // the ramp
    }
    for (int z = 6; z < kHeight; ++z) {  // walls y = 0 and y = kSide - 1
      keys.emplace_back(x, 0, z);
      keys.emplace_back(x, kSide - 1, z);
    }
  }
  for (int y = 1; y < kSide - 1; ++y) {
    for (int z = 6; z < kHeight; ++z) {  // walls x = 0 and x = kSide - 1
      keys.emplace_back(0, y, z);
      keys.emplace_back(kSide - 1, y, z);
    }
  }
  auto grid = VoxelGrid::FromKeys(kRoomResolutionM, keys);
  ASSERT_TRUE(grid.ok());
  GravityParams floors_only;
  floors_only.wall_up_rounds = 0;
  auto from_floor = EstimateGravityFrame(*grid, floors_only);
  auto from_both = EstimateGravityFrame(*grid, GravityParams{});
  ASSERT_TRUE(from_floor.ok() && from_both.ok());
  const double floor_error = AngleDeg(from_floor->up, Eigen::Vector3d::UnitZ());
  const double joint_error = AngleDeg(from_both->up, Eigen::Vector3d::UnitZ());
  EXPECT_GT(floor_error, 3.0);  // the ramp's normal
  EXPECT_LT(joint_error, 0.5 * floor_error);
  GravityParams bad;
  bad.wall_up_rounds = 11;
  EXPECT_NE(bad.Validate().message().find("wall_up_rounds"), std::string::npos);
}

TEST(GravityAlignmentTest, NoFloorIsAClearRefusal) {
  std::vector<VoxelKey> keys;  // one vertical wall: no floor, no ceiling
  for (int y = 0; y < 40; ++y) {
    for (int z = 0; z < 30; ++z) keys.emplace_back(0, y, z);
  }
  auto grid = VoxelGrid::FromKeys(kRoomResolutionM, keys);
  ASSERT_TRUE(grid.ok());
  const VoxelGrid& wall = *grid;
  auto frame = EstimateGravityFrame(wall, GravityParams{});
  ASSERT_FALSE(frame.ok());
  EXPECT_EQ(frame.status().code(), StatusCode::kFailedPrecondition);
  GravityParams bad;
  bad.yaw_peaks = 0;
  EXPECT_NE(bad.Validate().message().find("yaw_peaks"), std::string::npos);
}

}  // namespace
}  // namespace mapd::voxel
