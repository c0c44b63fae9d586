// FusionMode::kBounded against kExact: a revisited wall keeps a bounded number
// of nodes and publishes what the exact engine publishes.
#include <cmath>
#include <random>

#include <gtest/gtest.h>

#include "fusion/engine.h"

namespace mapd::fusion {
namespace {

using geometry::Segment2;
using geometry::Vec2;

FusionParams Mode(FusionMode mode) {
  FusionParams p;
  p.mode = mode;
  return p;
}

// An L-shaped corner and a straight wall, each seen by every observation with
// a few centimetres of endpoint noise and 5 mm of lateral noise: a site that a
// fleet drives past again and again.
std::vector<GroundFeature> View(ObservationId observation, std::mt19937_64* rng) {
  std::normal_distribution<double> along(0.0, 0.03), across(0.0, 0.005);
  const auto noisy = [&](Vec2 a, Vec2 b, bool vertical) {
    const Vec2 da = vertical ? Vec2(across(*rng), along(*rng)) : Vec2(along(*rng), across(*rng));
    const Vec2 db = vertical ? Vec2(across(*rng), along(*rng)) : Vec2(along(*rng), across(*rng));
    return Segment2{a + da, b + db};
  };
  const Segment2 walls[] = {noisy({0, 0}, {8, 0}, false), noisy({8, 0.2}, {8, 6}, true),
                            noisy({12, 3}, {20, 3}, false)};
  std::vector<GroundFeature> out;
  for (int k = 0; k < 3; ++k) {
    GroundFeature f;
    f.id = (observation << 4) | static_cast<FeatureId>(k);
    f.segment = walls[k];
    f.z_max_m = 2.0;
    out.push_back(f);
  }
  return out;
}

TEST(BoundedEngineTest, RevisitedWallsKeepFewNodesAndTheExactMap) {
  FusionEngine exact(Mode(FusionMode::kExact));
  FusionEngine bounded(Mode(FusionMode::kBounded));
  std::mt19937_64 rng(7);
  constexpr ObservationId kObservations = 3000;
  size_t nodes_at_half = 0;
  for (ObservationId o = 1; o <= kObservations; ++o) {
    const std::vector<GroundFeature> view = View(o, &rng);
    ASSERT_TRUE(exact.Add(o, o % 4, view).ok());
    ASSERT_TRUE(bounded.Add(o, o % 4, view).ok());
    if (o == kObservations / 2) nodes_at_half = bounded.node_count();
  }
  EXPECT_EQ(exact.node_count(), 3 * kObservations);
  EXPECT_EQ(bounded.feature_count(), 3 * kObservations);
  // Folding does its job: far fewer nodes, and the second half of the history
  // adds fewer nodes than the first.
  EXPECT_LT(bounded.node_count(), kObservations);
  EXPECT_LT(bounded.node_count() - nodes_at_half, nodes_at_half);

  const std::vector<FusedFeature> e = exact.Published();
  const std::vector<FusedFeature> b = bounded.Published();
  ASSERT_EQ(e.size(), 3u);
  ASSERT_EQ(b.size(), e.size());
  for (size_t i = 0; i < e.size(); ++i) {
    EXPECT_EQ(b[i].id, e[i].id);
    EXPECT_EQ(b[i].member_count, e[i].member_count);
    EXPECT_EQ(b[i].robots, e[i].robots);
    EXPECT_LE((b[i].segment.a - e[i].segment.a).norm(), 1e-6);
    EXPECT_LE((b[i].segment.b - e[i].segment.b).norm(), 1e-6);
    // Support past the exact cap is a count that may only overcount
    // (support_counter.h); here no two pieces ever merged, so it is exact.
    EXPECT_EQ(b[i].support, e[i].support);
  }
}

TEST(BoundedEngineTest, YoungClustersFoldNothing) {
  // Below the established support every feature stays a node, as in exact mode.
  FusionEngine bounded(Mode(FusionMode::kBounded));
  std::mt19937_64 rng(3);
  for (ObservationId o = 1; o <= 20; ++o) ASSERT_TRUE(bounded.Add(o, 0, View(o, &rng)).ok());
  EXPECT_EQ(bounded.node_count(), 60u);
}

TEST(BoundedEngineTest, RefusesTheSameObservationTwiceInARow) {
  FusionEngine bounded(Mode(FusionMode::kBounded));
  std::mt19937_64 rng(3);
  const std::vector<GroundFeature> view = View(1, &rng);
  ASSERT_TRUE(bounded.Add(1, 0, view).ok());
  const Status again = bounded.Add(1, 0, view);
  EXPECT_EQ(again.code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(bounded.feature_count(), 3u);
}

}  // namespace
}  // namespace mapd::fusion
