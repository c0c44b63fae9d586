// The plan-view yaw refinement: the best yaw near an off candidate, plan-view
// heights, no structure, non-finite yaws and bad parameters.
#include "voxel/yaw_refinement.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "voxel/support/corridor_scene.h"
#include "voxel/support/voxel_scene.h"

namespace mapd::voxel {
namespace {

using testing::GridOf;
using testing::Pose;
using testing::RasteriseSubmap;

const Eigen::Matrix3d kUpright = Eigen::Matrix3d::Identity();
constexpr double kGroveResolutionM = 0.25;
constexpr double kRadPerDeg = M_PI / 180.0;

double DegreesBetween(double x, double y) {
  return std::abs(std::remainder(x - y, 2 * M_PI)) / kRadPerDeg;
}

// Two crops of the generated grove, a third of which overlap; b is turned by
// 30 deg (the yaw that puts b back on a).
class YawRefinementTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    const testing::VoxelScene grove = testing::Grove();
    a_ = new VoxelGrid(GridOf(RasteriseSubmap(
        grove, Eigen::AlignedBox3d(Eigen::Vector3d(0.5, 0.5, -1), Eigen::Vector3d(24, 39.5, 6)),
        Eigen::Isometry3d::Identity(), kGroveResolutionM)));
    b_ = new VoxelGrid(GridOf(RasteriseSubmap(
        grove, Eigen::AlignedBox3d(Eigen::Vector3d(16, 0.5, -1), Eigen::Vector3d(39.5, 39.5, 6)),
        Pose(30, 0, 0, Eigen::Vector3d(14.3, -2.2, 0.4)), kGroveResolutionM)));
  }
  static void TearDownTestSuite() {
    delete a_;
    delete b_;
  }
  static VoxelGrid* a_;
  static VoxelGrid* b_;
};
VoxelGrid* YawRefinementTest::a_ = nullptr;
VoxelGrid* YawRefinementTest::b_ = nullptr;

// A candidate 8 deg off (as the wall histograms of outdoor maps give) gets
// a yaw within a degree of the truth added after the candidates; one within
// min_change_deg of its best gets none.
TEST_F(YawRefinementTest, AddsTheBestYawNearAnOffCandidate) {
  const double truth = 30 * kRadPerDeg;
  YawRefinementStats stats;
  auto refined =
      RefineYaws(*a_, kUpright, *b_, kUpright, {truth + 8 * kRadPerDeg, truth - 1 * kRadPerDeg},
                 kGroveResolutionM, YawRefinementParams{}, &stats);
  ASSERT_TRUE(refined.ok()) << refined.status().ToString();
  ASSERT_EQ(refined->size(), 3u);
  EXPECT_DOUBLE_EQ((*refined)[0], truth + 8 * kRadPerDeg);
  EXPECT_DOUBLE_EQ((*refined)[1], truth - 1 * kRadPerDeg);
  EXPECT_LE(DegreesBetween((*refined)[2], truth), 1.0);
  EXPECT_EQ(stats.yaws_added, 1);
  EXPECT_DOUBLE_EQ(stats.pixel_m, 2 * kGroveResolutionM);
  EXPECT_GT(stats.yaws_scored, 20);
  // Each window's best yaw and plan-view shift: the true window's put b's
  // centroid within two columns of where the truth puts it.
  ASSERT_EQ(stats.window_yaws.size(), 2u);
  ASSERT_EQ(stats.window_shifts_m.size(), 2u);
  EXPECT_LE(DegreesBetween(stats.window_yaws[1], truth), 1.0);
  Eigen::Vector3d centroid_b = Eigen::Vector3d::Zero();
  for (const Eigen::Vector3d& c : b_->occupied_centres()) centroid_b += c;
  centroid_b /= static_cast<double>(b_->num_occupied());
  const Eigen::Vector3d true_place = Pose(30, 0, 0, Eigen::Vector3d(14.3, -2.2, 0.4)) * centroid_b;
  const Eigen::Vector2d placed =
      (Eigen::AngleAxisd(stats.window_yaws[1], Eigen::Vector3d::UnitZ()) * centroid_b).head<2>() +
      stats.window_shifts_m[1];
  EXPECT_LE((placed - true_place.head<2>()).norm(), 2 * stats.pixel_m)
      << placed.transpose() << " vs " << true_place.head<2>().transpose();

  // A small image cap makes the columns coarser, not the call fail.
  YawRefinementParams small;
  small.max_pixels = 1000;
  YawRefinementStats coarse;
  auto capped = RefineYaws(*a_, kUpright, *b_, kUpright, {truth + 8 * kRadPerDeg},
                           kGroveResolutionM, small, &coarse);
  ASSERT_TRUE(capped.ok()) << capped.status().ToString();
  EXPECT_GT(coarse.pixel_m, 5 * stats.pixel_m);

  // With max_added 0, or switched off, the candidates pass through alone.
  YawRefinementParams none;
  none.max_added = 0;
  auto kept = RefineYaws(*a_, kUpright, *b_, kUpright, {truth + 8 * kRadPerDeg}, kGroveResolutionM,
                         none, nullptr);
  ASSERT_TRUE(kept.ok());
  EXPECT_EQ(kept->size(), 1u);
  YawRefinementParams off;
  off.enabled = false;
  auto same = RefineYaws(*a_, kUpright, *b_, kUpright, {truth + 8 * kRadPerDeg}, kGroveResolutionM,
                         off, nullptr);
  ASSERT_TRUE(same.ok());
  ASSERT_EQ(same->size(), 1u);
  EXPECT_DOUBLE_EQ(same->front(), truth + 8 * kRadPerDeg);
}

// The height that completes a placement: at the true yaw and horizontal
// shift, the grove's ground puts b within a voxel of its true height (0.4 m);
// a placement that shares no column, or is not finite, has none.
TEST_F(YawRefinementTest, PlanViewHeightsPutTheGroundOnTheGround) {
  const double truth = 30 * kRadPerDeg;
  const std::vector<double> heights =
      PlanViewHeights(*a_, kUpright, *b_, kUpright, {truth, truth, std::nan("")},
                      {Eigen::Vector2d(14.3, -2.2), Eigen::Vector2d(500, 0), Eigen::Vector2d(0, 0)},
                      2 * kGroveResolutionM);
  ASSERT_EQ(heights.size(), 3u);
  EXPECT_NEAR(heights[0], 0.4, kGroveResolutionM);
  EXPECT_TRUE(std::isnan(heights[1]));
  EXPECT_TRUE(std::isnan(heights[2]));
  // On two threads, each placement's height is the same, in its place.
  const std::vector<double> on_two =
      PlanViewHeights(*a_, kUpright, *b_, kUpright, {std::nan(""), truth, truth},
                      {Eigen::Vector2d(0, 0), Eigen::Vector2d(500, 0), Eigen::Vector2d(14.3, -2.2)},
                      2 * kGroveResolutionM, /*threads=*/2);
  ASSERT_EQ(on_two.size(), 3u);
  EXPECT_TRUE(std::isnan(on_two[0]));
  EXPECT_TRUE(std::isnan(on_two[1]));
  EXPECT_EQ(on_two[2], heights[0]);
  // The same crop with its frame 2 m lower (x_a = R x_b + t, t.z 2.4 m).
  const VoxelGrid raised = GridOf(RasteriseSubmap(
      testing::Grove(),
      Eigen::AlignedBox3d(Eigen::Vector3d(16, 0.5, -1), Eigen::Vector3d(39.5, 39.5, 6)),
      Pose(30, 0, 0, Eigen::Vector3d(14.3, -2.2, 2.4)), kGroveResolutionM));
  const std::vector<double> lower =
      PlanViewHeights(*a_, kUpright, raised, kUpright, {truth}, {Eigen::Vector2d(14.3, -2.2)},
                      2 * kGroveResolutionM);
  EXPECT_NEAR(lower[0], 2.4, kGroveResolutionM);
}

// Bad input gives NaN heights, one per placement, not a crash: a non-finite
// shift, a column edge that is zero or NaN, an empty map, fewer shifts than
// yaws.
TEST_F(YawRefinementTest, PlanViewHeightsOfBadInputAreNaN) {
  const double truth = 30 * kRadPerDeg;
  const double nan = std::nan("");
  const Eigen::Vector2d right(14.3, -2.2);
  const auto all_nan = [](const std::vector<double>& heights, std::size_t count) {
    return heights.size() == count &&
           std::all_of(heights.begin(), heights.end(), [](double h) { return std::isnan(h); });
  };
  EXPECT_TRUE(all_nan(
      PlanViewHeights(*a_, kUpright, *b_, kUpright, {truth}, {Eigen::Vector2d(nan, 0)}, 0.5), 1));
  EXPECT_TRUE(all_nan(
      PlanViewHeights(*a_, kUpright, *b_, kUpright, {truth, truth}, {right, right}, 0.0), 2));
  EXPECT_TRUE(all_nan(PlanViewHeights(*a_, kUpright, *b_, kUpright, {truth}, {right}, nan), 1));
  const VoxelGrid empty;
  EXPECT_TRUE(all_nan(PlanViewHeights(empty, kUpright, *b_, kUpright, {truth}, {right}, 0.5), 1));
  const std::vector<double> short_shifts =
      PlanViewHeights(*a_, kUpright, *b_, kUpright, {truth, truth}, {right}, 0.5);
  ASSERT_EQ(short_shifts.size(), 2u);
  EXPECT_NEAR(short_shifts[0], 0.4, kGroveResolutionM);
  EXPECT_TRUE(std::isnan(short_shifts[1]));
  EXPECT_TRUE(PlanViewHeights(*a_, kUpright, *b_, kUpright, {}, {}, 0.5).empty());
}

// A map with no column of upright structure (the lower 1.5 m of a wall: no
// voxel 2 m over its column's lowest) keeps the candidates.
TEST_F(YawRefinementTest, NoStructureKeepsTheCandidates) {
  const VoxelGrid low = GridOf(
      RasteriseSubmap(testing::FlatWall(),
                      Eigen::AlignedBox3d(Eigen::Vector3d(-1, -1, -1), Eigen::Vector3d(7, 1, 1.5)),
                      Eigen::Isometry3d::Identity(), kGroveResolutionM));
  auto refined = RefineYaws(low, kUpright, *b_, kUpright, {0.3}, kGroveResolutionM,
                            YawRefinementParams{}, nullptr);
  ASSERT_TRUE(refined.ok()) << refined.status().ToString();
  EXPECT_DOUBLE_EQ(refined->front(), 0.3);
}

TEST_F(YawRefinementTest, NonFiniteYawsAreRefused) {
  for (double bad : {std::nan(""), HUGE_VAL}) {
    auto refined = RefineYaws(*a_, kUpright, *b_, kUpright, {0.5, bad}, kGroveResolutionM,
                              YawRefinementParams{}, nullptr);
    EXPECT_EQ(refined.status().code(), StatusCode::kInvalidArgument);
    EXPECT_EQ(refined.status().message(), "yaw candidates must be finite");
  }
}

TEST(YawRefinementParamsTest, BadParamsAreNamed) {
  YawRefinementParams p;
  p.pixel_voxels = 0;
  EXPECT_NE(p.Validate().message().find("pixel_voxels"), std::string::npos);
  p = YawRefinementParams{};
  p.window_deg = 120;
  EXPECT_NE(p.Validate().message().find("window_deg"), std::string::npos);
  p = YawRefinementParams{};
  p.min_voxels_in_band = 0;
  EXPECT_NE(p.Validate().message().find("min_voxels_in_band"), std::string::npos);
  p = YawRefinementParams{};
  p.band_high_m = 1.0;  // below band_low_m
  EXPECT_NE(p.Validate().message().find("band_high_m"), std::string::npos);
  p = YawRefinementParams{};
  p.max_pixels = 10;
  EXPECT_NE(p.Validate().message().find("max_pixels"), std::string::npos);
  p = YawRefinementParams{};
  p.max_added = -1;
  EXPECT_NE(p.Validate().message().find("max_added"), std::string::npos);
  p = YawRefinementParams{};
  p.min_overlap_fraction = 0;
  EXPECT_NE(p.Validate().message().find("min_overlap_fraction"), std::string::npos);
  const VoxelGrid empty;
  EXPECT_EQ(RefineYaws(empty, kUpright, empty, kUpright, {0.0}, 0.1, p, nullptr).status().code(),
            StatusCode::kInvalidArgument);
}

}  // namespace
}  // namespace mapd::voxel
