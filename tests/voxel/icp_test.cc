// Point-to-point ICP: exact transforms, indexed targets and kept pairings bit
// for bit, bad input. Its neighbour search (NearestVoxelIndex) is checked
// against brute force in nearest_voxel_test.cc.
#include "voxel/icp.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <random>
#include <string>
#include <vector>

#include "voxel/octree_reader.h"
#include "voxel/support/corner_scene.h"
#include "voxel/support/voxel_scene.h"
#include "voxel/voxel_grid.h"

namespace mapd::voxel {

namespace {

using testing::kRoomResolutionM;
using testing::Pose;

std::vector<Eigen::Vector3d> Centres(const std::string& bytes) {
  auto tree = ReadOctree(bytes);
  EXPECT_TRUE(tree.ok()) << tree.status().ToString();
  auto grid = VoxelGrid::FromOcTree(**tree);
  EXPECT_TRUE(grid.ok());
  return grid->occupied_centres();
}

// The furnished room's occupied centres, A cropped to x in [-0.5, 5.6] m,
// B to [b_min_x, 9.5] m and rasterised in its own frame, T_a_b from A.
struct RoomPair {
  std::vector<Eigen::Vector3d> a, b;
};
RoomPair RasterisedRoomPair(const Eigen::Isometry3d& T_a_b, double b_min_x) {
  return {
      Centres(testing::RasteriseSubmap(testing::FurnishedRoom(), testing::RoomCropX(-0.5, 5.6),
                                       Eigen::Isometry3d::Identity(), kRoomResolutionM)),
      Centres(testing::RasteriseSubmap(testing::FurnishedRoom(), testing::RoomCropX(b_min_x, 9.5),
                                       T_a_b, kRoomResolutionM))};
}

// Two rasterisations of one room (different crops, B's grid rotated): ICP
// from a start 1 deg and ~1 voxel off lands within a fraction of a voxel.
TEST(IcpTest, RefinesAPerturbedStartOnRasterisedMaps) {
  const Eigen::Isometry3d T_a_b = Pose(23, 6, -4, Eigen::Vector3d(0.7, -1.2, 0.3));
  const auto [a, b] = RasterisedRoomPair(T_a_b, 2.2);
  const Eigen::Isometry3d start =
      Pose(1, 0, 0, Eigen::Vector3d(0.07, 0.05, -0.05)) * T_a_b;  // 1 deg, ~1 voxel at the origin
  auto result = RefineIcp(a, b, start, kRoomResolutionM, IcpParams());
  ASSERT_TRUE(result.ok()) << result.status().ToString();
  EXPECT_LT(testing::RotationErrorDeg(result->T_target_source, T_a_b), 0.3);
  EXPECT_LT(testing::TranslationError(result->T_target_source, T_a_b), 0.5 * kRoomResolutionM);
  EXPECT_GT(testing::RotationErrorDeg(start, T_a_b), 0.9);  // the test starts off, really
  EXPECT_LT(result->rms_residual_m, 0.8 * kRoomResolutionM);
  EXPECT_GT(result->inliers, 1000);
  EXPECT_GT(result->iterations, 1);
  EXPECT_TRUE(result->converged);
}

// Exact correspondences (the same points moved): recovered to numerical
// precision, both ways.
TEST(IcpTest, RecoversAnExactTransformAndItsInverse) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(0.0, 3.0);
  std::vector<Eigen::Vector3d> target;
  // Three perpendicular patches: a well-constrained shape.
  for (int i = 0; i < 3000; ++i) {
    const int face = i % 3;
    Eigen::Vector3d p(u(rng), u(rng), u(rng));
    p[face] = 0.0;
    target.push_back(p);
  }
  const Eigen::Isometry3d T_t_s = Pose(3, -1, 1.5, Eigen::Vector3d(0.08, -0.05, 0.1));
  std::vector<Eigen::Vector3d> source;
  for (const auto& p : target) source.push_back(T_t_s.inverse() * p);
  IcpParams params;
  params.convergence_rms_relative = 0.0;
  params.convergence_rotation_rad = 1e-10;
  params.convergence_translation_voxels = 1e-8;
  params.max_iterations = 100;
  auto forward = RefineIcp(target, source, Eigen::Isometry3d::Identity(), kRoomResolutionM, params);
  ASSERT_TRUE(forward.ok()) << forward.status().ToString();
  EXPECT_LT(testing::RotationErrorDeg(forward->T_target_source, T_t_s), 1e-3);
  EXPECT_LT(testing::TranslationError(forward->T_target_source, T_t_s), 1e-4);
  auto backward =
      RefineIcp(source, target, Eigen::Isometry3d::Identity(), kRoomResolutionM, params);
  ASSERT_TRUE(backward.ok());
  EXPECT_LT(testing::RotationErrorDeg(backward->T_target_source, T_t_s.inverse()), 1e-3);
  EXPECT_LT(testing::TranslationError(backward->T_target_source, T_t_s.inverse()), 1e-4);
}

// A target indexed once (IcpTarget) gives every run the result of the vector
// overload, bit for bit: from several starts, so that each run's overlap box
// leaves out a different part of the target (B is a crop of another part of
// the room, turned a little).
TEST(IcpTest, AnIndexedTargetGivesTheVectorOverloadsResultsBitForBit) {
  const Eigen::Isometry3d T_a_b = Pose(3, 1, -1, Eigen::Vector3d(0.4, -0.3, 0.1));
  const auto [a, b] = RasterisedRoomPair(T_a_b, 3.5);
  const IcpTarget target(&a, kRoomResolutionM);
  ASSERT_TRUE(target.status().ok());
  IcpParams params;
  params.max_source_points = 3000;
  for (const Eigen::Isometry3d& start : {Pose(1, 0, 0, Eigen::Vector3d(0.07, 0.05, -0.05)) * T_a_b,
                                         Pose(-4, 1, 0, Eigen::Vector3d(-0.3, 0.2, 0.1)) * T_a_b,
                                         Pose(8, 0, 0, Eigen::Vector3d(0.5, 0.0, 0.0)) * T_a_b,
                                         Pose(0, 0, 0, Eigen::Vector3d(0.25, 0.0, 0.0)) * T_a_b,
                                         Pose(0, 0, 0, Eigen::Vector3d(0.2, 0.1, 0.0)) * T_a_b}) {
    const auto want = RefineIcp(a, b, start, kRoomResolutionM, params);
    const auto got = RefineIcp(target, b, start, params);
    ASSERT_EQ(got.ok(), want.ok());
    if (!want.ok()) {
      EXPECT_EQ(got.status().ToString(), want.status().ToString());
      continue;
    }
    EXPECT_LT(want->target_points, a.size());  // the box left some of a out
    EXPECT_EQ(got->target_points, want->target_points);
    EXPECT_EQ(got->source_points, want->source_points);
    EXPECT_EQ(got->iterations, want->iterations);
    EXPECT_EQ(got->inliers, want->inliers);
    EXPECT_EQ(got->rms_residual_m, want->rms_residual_m);
    EXPECT_EQ(got->T_target_source.matrix(), want->T_target_source.matrix());
  }
}

// EvaluateIcp scores a given transform without moving it: a map against
// itself fits at the identity with no residual, and a quarter voxel along x
// leaves every voxel a quarter voxel from its own (its nearest).
TEST(IcpTest, EvaluateScoresTheGivenTransformWithoutRefiningIt) {
  const auto [a, b] = RasterisedRoomPair(Eigen::Isometry3d::Identity(), 3.5);
  const IcpTarget target(&a, kRoomResolutionM);
  ASSERT_TRUE(target.status().ok());
  const auto at_identity = EvaluateIcp(target, a, Eigen::Isometry3d::Identity());
  ASSERT_TRUE(at_identity.ok()) << at_identity.status().ToString();
  EXPECT_EQ(at_identity->rms_residual_m, 0.0);
  EXPECT_EQ(at_identity->iterations, 0);
  EXPECT_TRUE(at_identity->converged);
  Eigen::Isometry3d shifted = Eigen::Isometry3d::Identity();
  shifted.translation().x() = 0.25 * kRoomResolutionM;
  const auto off = EvaluateIcp(target, a, shifted);
  ASSERT_TRUE(off.ok()) << off.status().ToString();
  EXPECT_NEAR(off->rms_residual_m, 0.25 * kRoomResolutionM, 1e-6);
  EXPECT_EQ(off->T_target_source.matrix(), shifted.matrix());
  // The same checks as RefineIcp.
  IcpParams bad;
  bad.max_iterations = 0;
  EXPECT_EQ(EvaluateIcp(target, a, shifted, bad).status().code(), StatusCode::kInvalidArgument);
}

// Keeping pairings that provably still hold (IcpParams::reuse_pairings)
// changes no pair, so no result, bit for bit: from near and far starts, with
// either overload, trimmed or not. And it keeps most pairings: the test
// tests something only if the runs take several iterations.
TEST(IcpTest, KeptPairingsGiveTheSameResultsBitForBit) {
  const Eigen::Isometry3d T_a_b = Pose(3, 1, -1, Eigen::Vector3d(0.4, -0.3, 0.1));
  const auto [a, b] = RasterisedRoomPair(T_a_b, 3.5);
  const IcpTarget target(&a, kRoomResolutionM);
  ASSERT_TRUE(target.status().ok());
  int iterations = 0;
  std::size_t searches_kept = 0, searches_all = 0;
  for (const double trim : {1.0, 0.8}) {
    IcpParams searched;
    searched.trim_fraction = trim;
    searched.reuse_pairings = false;
    IcpParams kept = searched;
    kept.reuse_pairings = true;
    for (const Eigen::Isometry3d& start :
         {Pose(1, 0, 0, Eigen::Vector3d(0.07, 0.05, -0.05)) * T_a_b,
          Pose(-4, 1, 0, Eigen::Vector3d(-0.3, 0.2, 0.1)) * T_a_b,
          Pose(8, 0, 0, Eigen::Vector3d(0.5, 0.0, 0.0)) * T_a_b,
          Pose(0, 2, 0, Eigen::Vector3d(0.2, 0.1, 0.0)) * T_a_b}) {
      const auto want = RefineIcp(a, b, start, kRoomResolutionM, searched);
      for (const auto& got :
           {RefineIcp(a, b, start, kRoomResolutionM, kept), RefineIcp(target, b, start, kept)}) {
        ASSERT_EQ(got.ok(), want.ok());
        if (!want.ok()) {
          EXPECT_EQ(got.status().ToString(), want.status().ToString());
          continue;
        }
        EXPECT_EQ(got->iterations, want->iterations);
        EXPECT_EQ(got->inliers, want->inliers);
        EXPECT_EQ(got->rms_residual_m, want->rms_residual_m);
        EXPECT_EQ(got->T_target_source.matrix(), want->T_target_source.matrix());
      }
      if (!want.ok()) continue;
      iterations += want->iterations;
      EXPECT_EQ(want->searches, want->source_points * (want->iterations + 1));
      const auto got = RefineIcp(target, b, start, kept);
      searches_kept += got->searches;
      searches_all += want->searches;
    }
  }
  EXPECT_GT(iterations, 40);
  EXPECT_LT(searches_kept, searches_all * 3 / 4);
}

TEST(IcpTest, AnIndexedTargetRejectsWhatTheVectorOverloadRejects) {
  std::vector<Eigen::Vector3d> points(20, Eigen::Vector3d::Ones());
  const IcpTarget no_size(&points, 0.0);
  auto result = RefineIcp(no_size, points, Eigen::Isometry3d::Identity());
  EXPECT_EQ(result.status().code(), StatusCode::kInvalidArgument);
  EXPECT_NE(result.status().message().find("voxel size"), std::string::npos);
  std::vector<Eigen::Vector3d> bad = points;
  bad[3].x() = std::nan("");
  const IcpTarget not_finite(&bad, kRoomResolutionM);
  result = RefineIcp(not_finite, points, Eigen::Isometry3d::Identity());
  EXPECT_EQ(result.status().code(), StatusCode::kInvalidArgument);
  const IcpTarget good(&points, kRoomResolutionM);
  result = RefineIcp(good, bad, Eigen::Isometry3d::Identity());
  EXPECT_EQ(result.status().code(), StatusCode::kInvalidArgument);
  IcpParams params;
  params.min_inliers = 0;
  result = RefineIcp(good, points, Eigen::Isometry3d::Identity(), params);
  EXPECT_NE(result.status().message().find("icp.min_inliers"), std::string::npos);
}

TEST(IcpTest, NoOverlapIsAFailedPrecondition) {
  const std::vector<Eigen::Vector3d> target(50, Eigen::Vector3d::Zero());
  std::vector<Eigen::Vector3d> source;
  for (int i = 0; i < 50; ++i) source.emplace_back(100.0 + i * 0.1, 0.0, 0.0);
  auto result = RefineIcp(target, source, Eigen::Isometry3d::Identity(), kRoomResolutionM);
  ASSERT_FALSE(result.ok());
  EXPECT_EQ(result.status().code(), StatusCode::kFailedPrecondition);
}

TEST(IcpTest, RejectsBadParametersAndInput) {
  const std::vector<Eigen::Vector3d> points(20, Eigen::Vector3d::Ones());
  IcpParams params;
  params.max_correspondence_voxels = 0.0;
  auto result = RefineIcp(points, points, Eigen::Isometry3d::Identity(), kRoomResolutionM, params);
  ASSERT_FALSE(result.ok());
  EXPECT_NE(result.status().message().find("icp.max_correspondence_voxels"), std::string::npos);
  result = RefineIcp(points, points, Eigen::Isometry3d::Identity(), 0.0);
  EXPECT_EQ(result.status().code(), StatusCode::kInvalidArgument);
  std::vector<Eigen::Vector3d> bad = points;
  bad[3].x() = std::nan("");
  result = RefineIcp(points, bad, Eigen::Isometry3d::Identity(), kRoomResolutionM);
  EXPECT_EQ(result.status().code(), StatusCode::kInvalidArgument);
}

}  // namespace
}  // namespace mapd::voxel
