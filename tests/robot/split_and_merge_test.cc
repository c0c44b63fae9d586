// Split-and-merge line extraction from a laser scan: splits at corners, never
// bridges gaps, drops short pieces, rejoins needless cuts.
#include "client/robot/split_and_merge.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <utility>
#include <vector>

namespace mapd::robot {
namespace {

// n points evenly spaced from a to b, both included.
std::vector<Vec2> Sample(const Vec2& a, const Vec2& b, int n) {
  std::vector<Vec2> out;
  for (int i = 0; i < n; ++i) out.push_back(a + (b - a) * (static_cast<double>(i) / (n - 1)));
  return out;
}

// Endpoint distance, whichever way round.
double SegmentDistance(const Segment2& s, const Segment2& t) {
  return std::min(std::max((s.a - t.a).norm(), (s.b - t.b).norm()),
                  std::max((s.a - t.b).norm(), (s.b - t.a).norm()));
}

TEST(SplitAndMergeTest, StraightRunIsOneSegmentClippedToItsPoints) {
  const std::vector<Vec2> points = Sample({1, 2}, {4, 6}, 30);
  const std::vector<ExtractedLine> lines = SplitAndMerge(points, SplitAndMergeParams());
  ASSERT_EQ(lines.size(), 1u);
  EXPECT_LE(SegmentDistance(lines[0].segment, {{1, 2}, {4, 6}}), 1e-9);
  EXPECT_EQ(lines[0].first, 0u);
  EXPECT_EQ(lines[0].last, 29u);
  EXPECT_NEAR(lines[0].rms_m, 0.0, 1e-6);  // sqrt of rounding noise
}

TEST(SplitAndMergeTest, CornerSplitsIntoTwoWalls) {
  std::vector<Vec2> points = Sample({0, 0}, {3, 0}, 31);
  const std::vector<Vec2> up = Sample({3, 0}, {3, 2}, 21);
  points.insert(points.end(), up.begin() + 1, up.end());  // the corner once
  const std::vector<ExtractedLine> lines = SplitAndMerge(points, SplitAndMergeParams());
  ASSERT_EQ(lines.size(), 2u);
  EXPECT_LE(SegmentDistance(lines[0].segment, {{0, 0}, {3, 0}}), 1e-9);
  EXPECT_LE(SegmentDistance(lines[1].segment, {{3, 0}, {3, 2}}), 1e-9);
}

TEST(SplitAndMergeTest, NeverBridgesAGap) {
  // Two collinear pieces 0.5 m apart: one line with a large gap, two without.
  std::vector<Vec2> points = Sample({0, 0}, {2, 0}, 21);
  const std::vector<Vec2> far = Sample({2.5, 0}, {4.5, 0}, 21);
  points.insert(points.end(), far.begin(), far.end());
  SplitAndMergeParams params;
  params.max_gap_m = 0.3;
  EXPECT_EQ(SplitAndMerge(points, params).size(), 2u);
  params.max_gap_m = 0.6;
  EXPECT_EQ(SplitAndMerge(points, params).size(), 1u);
}

TEST(SplitAndMergeTest, GapGrowsWithRangeWhenAsked) {
  // The same 0.5 m gap 10 m from the origin: bridged once the limit grows by
  // 0.03 per metre of range (0.3 + 0.3 = 0.6 m), not with a fixed limit.
  std::vector<Vec2> points = Sample({10, 0}, {10, 2}, 21);
  const std::vector<Vec2> far = Sample({10, 2.5}, {10, 4.5}, 21);
  points.insert(points.end(), far.begin(), far.end());
  SplitAndMergeParams params;
  params.max_gap_m = 0.3;
  EXPECT_EQ(SplitAndMerge(points, params).size(), 2u);
  params.gap_per_range = 0.03;
  EXPECT_EQ(SplitAndMerge(points, params).size(), 1u);
}

TEST(SplitAndMergeTest, MissingReturnsEndARun) {
  // A NaN between two close collinear pieces (a beam without a return) cuts the
  // wall, and no line uses the NaN.
  std::vector<Vec2> points = Sample({0, 0}, {2, 0}, 21);
  points.push_back(Vec2(NAN, NAN));
  const std::vector<Vec2> rest = Sample({2.1, 0}, {4, 0}, 20);
  points.insert(points.end(), rest.begin(), rest.end());
  points.push_back(Vec2(NAN, NAN));
  const std::vector<ExtractedLine> lines = SplitAndMerge(points, SplitAndMergeParams());
  ASSERT_EQ(lines.size(), 2u);
  EXPECT_EQ(lines[0].last, 20u);
  EXPECT_EQ(lines[1].first, 22u);
  EXPECT_EQ(lines[1].last, 41u);
  EXPECT_TRUE(lines[1].segment.a.allFinite() && lines[1].segment.b.allFinite());
}

TEST(SplitAndMergeTest, DropsShortAndSparsePieces) {
  SplitAndMergeParams params;
  params.min_points = 6;
  params.min_length_m = 0.3;
  EXPECT_TRUE(SplitAndMerge(Sample({0, 0}, {1, 0}, 5), params).empty());     // too few points
  EXPECT_TRUE(SplitAndMerge(Sample({0, 0}, {0.2, 0}, 20), params).empty());  // too short
  EXPECT_EQ(SplitAndMerge(Sample({0, 0}, {1, 0}, 6), params).size(), 1u);
}

TEST(SplitAndMergeTest, SpikeAboveThresholdCutsTheWall) {
  // A straight wall with a bump below split_m stays one line; a spike above
  // split_m cuts it, and the two-point pieces around the spike are dropped.
  std::vector<Vec2> points = Sample({0, 0}, {4, 0}, 41);
  points[20].y() = 0.03;
  EXPECT_EQ(SplitAndMerge(points, SplitAndMergeParams()).size(), 1u);
  points[20].y() = 0.3;
  const std::vector<ExtractedLine> lines = SplitAndMerge(points, SplitAndMergeParams());
  ASSERT_EQ(lines.size(), 2u);
  EXPECT_LT(lines[0].last, lines[1].first + 1);
}

TEST(SplitAndMergeTest, NoisyRoomFromAScanHasItsWalls) {
  // A robot at the centre of a 6 x 4 m room, 360 beams with 1 cm range noise.
  std::mt19937 rng(7);
  std::normal_distribution<double> noise(0.0, 0.01);
  std::vector<Vec2> points;
  for (int i = 0; i < 360; ++i) {
    const double angle = -M_PI + 2.0 * M_PI * i / 360.0;
    const Vec2 u(std::cos(angle), std::sin(angle));
    // Distance to the box |x| <= 3, |y| <= 2 along u.
    const double r = std::min(std::abs(u.x()) > 1e-12 ? 3.0 / std::abs(u.x()) : 1e9,
                              std::abs(u.y()) > 1e-12 ? 2.0 / std::abs(u.y()) : 1e9);
    points.push_back((r + noise(rng)) * u);
  }
  const std::vector<ExtractedLine> lines = SplitAndMerge(points, SplitAndMergeParams());
  // Four walls; the wall at x = -3 is cut by the scan's start and end into two.
  // A short piece may remain at a corner that falls between two beams.
  size_t long_lines = 0;
  for (const ExtractedLine& line : lines) {
    EXPECT_LT(line.rms_m, 0.02);
    if (line.segment.length() < 1.0) continue;
    ++long_lines;
    const Vec2 d = line.segment.direction().normalized();
    EXPECT_GT(std::max(std::abs(d.x()), std::abs(d.y())), std::cos(1.0 * M_PI / 180.0));
  }
  EXPECT_EQ(long_lines, 5u);
  EXPECT_LE(lines.size(), 7u);
}

// Variants (SplitAndMergeParams: the synthetic city's extractor flips all four).

// A polyline through `corners`, n points per edge, each corner once.
std::vector<Vec2> Polyline(const std::vector<Vec2>& corners, int n) {
  std::vector<Vec2> out = {corners.front()};
  for (size_t i = 1; i < corners.size(); ++i) {
    const std::vector<Vec2> edge = Sample(corners[i - 1], corners[i], n + 1);
    out.insert(out.end(), edge.begin() + 1, edge.end());
  }
  return out;
}

TEST(SplitAndMergeTest, SplitPointGoesToTheFirstPieceOnlyWhenAsked) {
  const std::vector<Vec2> points = Polyline({{0, 0}, {3, 0}, {3, 2}}, 30);  // corner: index 30
  SplitAndMergeParams params;
  std::vector<ExtractedLine> lines = SplitAndMerge(points, params);
  ASSERT_EQ(lines.size(), 2u);
  EXPECT_EQ(lines[0].last, 30u);
  EXPECT_EQ(lines[1].first, 30u);  // the default: the corner is in both walls
  params.split_point_in_both = false;
  lines = SplitAndMerge(points, params);
  ASSERT_EQ(lines.size(), 2u);
  EXPECT_EQ(lines[0].last, 30u);
  EXPECT_EQ(lines[1].first, 31u);
  EXPECT_LE(SegmentDistance(lines[0].segment, {{0, 0}, {3, 0}}), 1e-9);
  // The second wall starts at its first own point, one beam past the corner.
  EXPECT_LE(SegmentDistance(lines[1].segment, {{3, 2.0 / 30.0}, {3, 2}}), 1e-9);
}

TEST(SplitAndMergeTest, MergeRejoinsAWallTheSplitCutNeedlessly) {
  // The whole run's chord makes (2, -0.01) the farthest point (12 cm), and the
  // rest is cut again at (3, 0.05) (5.5 cm from its chord): three pieces. The
  // first two joined stay within split_m (4.3 cm), so the merge makes them one,
  // whether or not the pieces share their break point.
  const std::vector<Vec2> points = Polyline({{0, 0}, {2, -0.01}, {3, 0.05}, {4, 0.22}}, 10);
  using Pieces = std::vector<std::pair<size_t, size_t>>;  // first, last
  const struct {
    bool in_both;
    bool merge;
    Pieces expected;
  } cases[] = {
      {true, true, {{0, 20}, {20, 30}}},
      {true, false, {{0, 10}, {10, 20}, {20, 30}}},
      {false, true, {{0, 20}, {21, 30}}},
      {false, false, {{0, 10}, {11, 20}, {21, 30}}},
  };
  for (const auto& c : cases) {
    SplitAndMergeParams params;
    params.split_m = 0.05;
    params.split_point_in_both = c.in_both;
    params.merge_neighbours = c.merge;
    Pieces pieces;
    for (const ExtractedLine& line : SplitAndMerge(points, params)) {
      pieces.emplace_back(line.first, line.last);
    }
    EXPECT_EQ(pieces, c.expected) << "split_point_in_both " << c.in_both << ", merge " << c.merge;
  }
}

TEST(SplitAndMergeTest, GapFromTheJoiningPointDependsOnScanDirection) {
  // Two collinear pieces 2 m apart, 18 m and 16 m from the origin at the gap.
  // Limit 0.3 + 0.1 r: 2.1 m with the farther point's range (bridged either
  // way round), 1.9 m with the joining point's when the scan runs inwards.
  std::vector<Vec2> inwards = Sample({20, 0}, {18, 0}, 21);
  const std::vector<Vec2> near = Sample({16, 0}, {14, 0}, 21);
  inwards.insert(inwards.end(), near.begin(), near.end());
  const std::vector<Vec2> outwards(inwards.rbegin(), inwards.rend());
  SplitAndMergeParams params;
  params.max_gap_m = 0.3;
  params.gap_per_range = 0.1;
  EXPECT_EQ(SplitAndMerge(inwards, params).size(), 1u);
  EXPECT_EQ(SplitAndMerge(outwards, params).size(), 1u);
  params.gap_from_farther_point = false;
  EXPECT_EQ(SplitAndMerge(inwards, params).size(), 2u);
  EXPECT_EQ(SplitAndMerge(outwards, params).size(), 1u);
}

TEST(SplitAndMergeTest, EndsFromFirstAndLastPointWhenNotClipped) {
  // A wall scanned from x = 3 to x = 0 whose second point overshoots to 3.05.
  std::vector<Vec2> points = Sample({3, 0}, {0, 0}, 31);
  points[1] = Vec2(3.05, 0);
  SplitAndMergeParams params;
  std::vector<ExtractedLine> lines = SplitAndMerge(points, params);
  ASSERT_EQ(lines.size(), 1u);
  EXPECT_NEAR(lines[0].segment.length(), 3.05, 1e-9);  // the extremes: all the points
  params.clip_to_extremes = false;
  lines = SplitAndMerge(points, params);
  ASSERT_EQ(lines.size(), 1u);
  // The projections of the first and last point, in input order.
  EXPECT_LE((lines[0].segment.a - Vec2(3, 0)).norm(), 1e-9);
  EXPECT_LE((lines[0].segment.b - Vec2(0, 0)).norm(), 1e-9);
}

TEST(SplitAndMergeTest, EmptyAndTinyInputs) {
  EXPECT_TRUE(SplitAndMerge({}, SplitAndMergeParams()).empty());
  EXPECT_TRUE(SplitAndMerge({Vec2(1, 1)}, SplitAndMergeParams()).empty());
}

}  // namespace
}  // namespace mapd::robot
