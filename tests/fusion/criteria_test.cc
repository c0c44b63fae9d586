// The paper's three criteria one by one (included angle, overlap of the
// feature circles, centre distance) and their conjunction, symmetric bit for bit.
#include "fusion/criteria.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace mapd::fusion {
namespace {

using geometry::Segment2;

TEST(IncludedAngleTest, PerpendicularAntiparallelAndSkew) {
  const Segment2 x{{0, 0}, {2, 0}};
  EXPECT_NEAR(IncludedAngle(x, {{1, 1}, {1, 5}}), M_PI / 2, 1e-15);
  EXPECT_EQ(IncludedAngle(x, {{3, 0}, {-1, 0}}), 0.0);  // antiparallel: |u.v| makes it 0
  EXPECT_NEAR(IncludedAngle(x, {{0, 0}, {-1, 1}}), M_PI / 4, 1e-15);  // 135 deg -> 45 deg
}

TEST(OverlapRatioTest, DisjointCirclesDoNotOverlap) {
  EXPECT_EQ(OverlapRatio({{0, 0}, 1.0}, {{5, 0}, 1.0}), 0.0);
}

TEST(OverlapRatioTest, ExternallyTangentCirclesDoNotOverlap) {
  // D = R_f + R_g exactly: eps = 0 (docs/algorithms.md Eq. 9).
  EXPECT_EQ(OverlapRatio(CircleOf({{0, 0}, {2, 0}}), CircleOf({{2, 0}, {4, 0}})), 0.0);
}

TEST(OverlapRatioTest, NestedAndInternallyTangentCirclesOverlapFully) {
  EXPECT_EQ(OverlapRatio({{5, 0}, 5.0}, {{5, 0}, 1.0}), 1.0);
  EXPECT_EQ(OverlapRatio({{5, 0}, 5.0}, {{9, 0}, 1.0}), 1.0);  // D = |R_f - R_g|
}

TEST(OverlapRatioTest, TwoUnitCirclesOneApart) {
  // D = 1, R_f = R_g = 1: alpha = acos((1 + 1 - 1) / 2) = pi/3 for both, so
  // lens = pi/3 + pi/3 - 1 * 1 * sin(pi/3) = 2 pi/3 - sqrt(3)/2 = 1.228369699...
  // and eps = lens / pi = 0.391002218...
  const double lens = 2.0 * M_PI / 3.0 - std::sqrt(3.0) / 2.0;
  EXPECT_NEAR(OverlapRatio(CircleOf({{-1, 0}, {1, 0}}), CircleOf({{0, 0}, {2, 0}})), lens / M_PI,
              1e-14);
  EXPECT_NEAR(lens / M_PI, 0.391002218, 1e-9);
}

TEST(OverlapRatioTest, UnequalCircles) {
  // R_f = 2, R_g = 1, D = 2: alpha_f = acos((4 + 4 - 1) / 8) = acos(7/8),
  // alpha_g = acos((4 + 1 - 4) / 4) = acos(1/4);
  // lens = 4 acos(7/8) + acos(1/4) - 2 * 2 * sin(acos(7/8)) = 2.021442 + 1.318116 - 1.936492
  //      = 1.403066 (sin(acos(7/8)) = sqrt(15)/8); eps = lens / (pi * 1^2) = 0.446610.
  const double lens = 4.0 * std::acos(7.0 / 8.0) + std::acos(0.25) - 4.0 * std::sqrt(15.0) / 8.0;
  EXPECT_NEAR(OverlapRatio({{0, 0}, 2.0}, {{2, 0}, 1.0}), lens / M_PI, 1e-14);
  EXPECT_NEAR(lens / M_PI, 0.446610, 1e-6);
}

TEST(MaxCentreDistanceTest, UsesClampedSegmentDistance) {
  // O_g = (6, 1) is nearest to f's endpoint (2, 0); O_f = (1, 0) to g's endpoint (5, 1).
  EXPECT_DOUBLE_EQ(MaxCentreDistance({{0, 0}, {2, 0}}, {{5, 1}, {7, 1}}), std::sqrt(17.0));
  // Asymmetric: O_g = (10, 0.3) is 0.3 m from f, O_f = (5, 0) is |(3, 0.3)| from g.
  EXPECT_DOUBLE_EQ(MaxCentreDistance({{0, 0}, {10, 0}}, {{8, 0.3}, {12, 0.3}}), std::sqrt(9.09));
}

TEST(MeetsAllCriteriaTest, ParallelWallsAcrossARoadFailCriterion2) {
  const Segment2 left{{0, 0}, {10, 0}};
  const Segment2 right{{0, 20}, {10, 20}};
  EXPECT_LE(IncludedAngle(left, right), FusionParams().delta_rad);                 // 1 passes
  EXPECT_LT(OverlapRatio(CircleOf(left), CircleOf(right)), FusionParams().gamma);  // 2 fails
  EXPECT_FALSE(MeetsAllCriteria(left, right, FusionParams()));
}

TEST(MeetsAllCriteriaTest, FenceBesideAWallFailsCriterion3) {
  // The paper's Figure 5: wall FG and a short fence HJ 1.5 m in front of it.
  const Segment2 wall{{0, 0}, {10, 0}};
  const Segment2 fence{{3, 1.5}, {7, 1.5}};
  const FusionParams params;
  EXPECT_LE(IncludedAngle(wall, fence), params.delta_rad);        // 1 passes
  EXPECT_EQ(OverlapRatio(CircleOf(wall), CircleOf(fence)), 1.0);  // 2 passes
  EXPECT_DOUBLE_EQ(MaxCentreDistance(wall, fence), 1.5);          // 3 fails
  EXPECT_FALSE(MeetsAllCriteria(wall, fence, params));
}

TEST(MeetsAllCriteriaTest, TwoScansOfTheSameWallPass) {
  EXPECT_TRUE(MeetsAllCriteria({{0, 0}, {5, 0.05}}, {{1, 0.02}, {6, 0.0}}, FusionParams()));
}

TEST(MeetsAllCriteriaTest, IsSymmetricBitForBit) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-3.0, 3.0);
  FusionParams params;
  params.gamma = 0.0;  // evaluate every criterion often
  for (int i = 0; i < 20000; ++i) {
    const Segment2 f{{u(rng), u(rng)}, {u(rng), u(rng)}};
    const Segment2 g{{u(rng), u(rng)}, {u(rng), u(rng)}};
    ASSERT_EQ(OverlapRatio(CircleOf(f), CircleOf(g)), OverlapRatio(CircleOf(g), CircleOf(f)));
    ASSERT_EQ(IncludedAngle(f, g), IncludedAngle(g, f));
    ASSERT_EQ(MaxCentreDistance(f, g), MaxCentreDistance(g, f));
  }
}

}  // namespace
}  // namespace mapd::fusion
