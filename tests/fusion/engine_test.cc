// FusionEngine on small hand-made scenes: fusing, publication at min_support,
// refused input, the change feed, corner snapping and the chain guard.
#include "fusion/engine.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "fusion/engine_inspector.h"

namespace mapd::fusion {

// gtest prints parameters with this (not as bytes).
void PrintTo(CornerMode mode, std::ostream* out) { *out << CornerModeName(mode); }

namespace {

using geometry::Vec2;
using ::testing::ElementsAre;
using ::testing::IsEmpty;

GroundFeature Wall(FeatureId id, Vec2 a, Vec2 b) {
  GroundFeature f;
  f.id = id;
  f.segment = {a, b};
  f.z_max_m = 2.5;
  return f;
}

// The exact engine: these tests name members, which bounded mode folds away.
FusionParams Support(uint32_t min_support) {
  FusionParams p;
  p.mode = FusionMode::kExact;
  p.min_support = min_support;
  return p;
}

void ExpectNear(const Vec2& actual, const Vec2& expected, double tolerance_m) {
  EXPECT_LE((actual - expected).norm(), tolerance_m)
      << actual.transpose() << " vs " << expected.transpose();
}

TEST(FusionEngineTest, TwoObservationsOfOneWallFuse) {
  // Two walls 10 cm apart fit their TLS line with an RMS of 5 cm, at the chain
  // guard's default bound: the guard is off here, this test is the paper's fit.
  FusionParams params = Support(2);
  params.chain_max_rms_m = 0.0;
  FusionEngine engine(params);
  ASSERT_TRUE(engine.Add(1, 7, {Wall(10, {0, 0}, {10, 0})}).ok());
  ASSERT_TRUE(engine.Add(2, 8, {Wall(20, {0, 0.1}, {10, 0.1})}).ok());
  EXPECT_EQ(engine.feature_count(), 2u);
  EXPECT_EQ(engine.cluster_count(), 1u);
  const std::vector<FusedFeature> published = engine.Published();
  ASSERT_EQ(published.size(), 1u);
  const FusedFeature& f = published[0];
  EXPECT_EQ(f.id, 10u);
  EXPECT_EQ(f.support, 2u);
  EXPECT_EQ(f.member_count, 2u);
  EXPECT_THAT(f.robots, ElementsAre(7u, 8u));
  // The TLS line is y = 0.05; the extreme projections are x = 0 and x = 10.
  const Vec2 lo = f.fitted.a.x() < f.fitted.b.x() ? f.fitted.a : f.fitted.b;
  const Vec2 hi = f.fitted.a.x() < f.fitted.b.x() ? f.fitted.b : f.fitted.a;
  ExpectNear(lo, {0.0, 0.05}, 1e-12);
  ExpectNear(hi, {10.0, 0.05}, 1e-12);
  EXPECT_EQ(f.z_max_m, 2.5);
}

TEST(FusionEngineTest, FeaturesOfOneObservationNeverLinkDirectly) {
  FusionEngine engine(Support(1));
  ASSERT_TRUE(engine.Add(1, 0, {Wall(1, {0, 0}, {10, 0}), Wall(2, {0, 0.05}, {10, 0.05})}).ok());
  EXPECT_EQ(engine.cluster_count(), 2u);
  // A later observation of the wall links to both: one cluster through it.
  ASSERT_TRUE(engine.Add(2, 0, {Wall(3, {0, 0.02}, {10, 0.02})}).ok());
  EXPECT_EQ(engine.cluster_count(), 1u);
  EXPECT_THAT(EngineInspector::Partition(engine), ElementsAre(ElementsAre(1u, 2u, 3u)));
}

TEST(FusionEngineTest, PublishesAtMinSupport) {
  FusionEngine engine(Support(3));
  ChangeFeed feed;
  ASSERT_TRUE(engine.Add(1, 0, {Wall(1, {0, 0}, {10, 0})}, &feed).ok());
  ASSERT_TRUE(engine.Add(2, 0, {Wall(2, {0, 0}, {10, 0})}, &feed).ok());
  EXPECT_TRUE(feed.empty());
  EXPECT_EQ(engine.published_count(), 0u);
  ASSERT_TRUE(engine.Get(1).has_value());  // kept, not published
  EXPECT_EQ(engine.Get(1)->support, 2u);
  EXPECT_FALSE(engine.Get(2).has_value());  // a member, not a cluster name
  ASSERT_TRUE(engine.Add(3, 0, {Wall(3, {0, 0}, {10, 0})}, &feed).ok());
  EXPECT_THAT(feed.added, ElementsAre(1u));
  EXPECT_EQ(engine.published_count(), 1u);
}

TEST(FusionEngineTest, RefusedInputLeavesTheEngineUnchanged) {
  FusionEngine engine(Support(1));
  ASSERT_TRUE(engine.Add(1, 0, {Wall(1, {0, 0}, {10, 0})}).ok());
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const std::vector<std::vector<GroundFeature>> bad = {
      {Wall(5, {0, 0}, {10, 0}), Wall(6, {nan, 0}, {1, 0})},  // NaN after a valid one
      {Wall(5, {3, 3}, {3, 3})},                              // zero length
      {Wall(5, {2e6, 0}, {1, 0})},                            // absurd coordinate
      {Wall(1, {0, 0}, {10, 0})},                             // reused feature id
      {Wall(5, {0, 0}, {10, 0}), Wall(5, {0, 1}, {10, 1})},   // duplicate within the batch
  };
  for (const auto& features : bad) {
    const Status s = engine.Add(2, 0, features);
    EXPECT_EQ(s.code(), StatusCode::kInvalidArgument) << s.ToString();
    EXPECT_EQ(engine.feature_count(), 1u);
    EXPECT_EQ(engine.published_count(), 1u);
    EXPECT_EQ(engine.Published()[0].member_count, 1u);
  }
  const Status reused = engine.Add(1, 0, {Wall(5, {0, 0}, {10, 0})});
  EXPECT_EQ(reused.code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(engine.feature_count(), 1u);
  // After all those refusals, observation 2 and feature 5 are still free.
  EXPECT_TRUE(engine.Add(2, 0, {Wall(5, {0, 0}, {10, 0})}).ok());
  EXPECT_EQ(engine.feature_count(), 2u);
}

// A feature id twice in one batch names the later one, whether the batch is
// scanned (small) or checked through a set (64 features and more).
TEST(FusionEngineTest, ADuplicateIdInABatchNamesTheLaterFeature) {
  for (const size_t size : {3u, 70u}) {
    FusionEngine engine(Support(1));
    std::vector<GroundFeature> batch;
    for (size_t i = 0; i < size; ++i) {
      const double y = static_cast<double>(i);
      batch.push_back(Wall(100 + i, {0, y}, {5, y}));
    }
    const size_t later = size - 1;
    batch[later].id = batch[1].id;
    const Status s = engine.Add(1, 0, batch);
    EXPECT_EQ(s.code(), StatusCode::kInvalidArgument);
    EXPECT_EQ(s.message(), "features[" + std::to_string(later) + "]: feature id 101 is not unique");
    EXPECT_EQ(engine.feature_count(), 0u);
  }
}

// Support counts distinct observations, not members: one scan that sees a wall
// as several segments counts once (proto FusedFeature.support).
TEST(FusionEngineTest, SupportCountsDistinctObservations) {
  FusionEngine once(Support(2));
  ASSERT_TRUE(
      once.Add(1, 0, {Wall(1, {0, 0}, {6, 0}), Wall(2, {4, 0}, {10, 0}), Wall(3, {2, 0}, {8, 0})})
          .ok());
  EXPECT_EQ(once.published_count(), 0u) << "three segments of one scan are support 1";

  FusionEngine engine(Support(3));
  ASSERT_TRUE(engine.Add(1, 0, {Wall(1, {0, 0}, {6, 0}), Wall(2, {4, 0}, {10, 0})}).ok());
  ASSERT_TRUE(engine.Add(2, 0, {Wall(3, {0, 0.01}, {10, 0.01})}).ok());
  EXPECT_EQ(engine.published_count(), 0u);
  ASSERT_TRUE(engine.Add(3, 7, {Wall(4, {0, -0.01}, {10, -0.01})}).ok());
  ASSERT_EQ(engine.published_count(), 1u);
  const FusedFeature f = engine.Published()[0];
  EXPECT_EQ(f.support, 3u);
  EXPECT_EQ(f.member_count, 4u);
  EXPECT_THAT(f.robots, ElementsAre(0u, 7u));
}

TEST(FusionEngineTest, ChangeFeedReportsAddedUpdatedRemoved) {
  FusionEngine engine(Support(1));
  ChangeFeed feed;
  ASSERT_TRUE(engine.Add(1, 0, {Wall(1, {0, 0}, {4, 0})}, &feed).ok());
  EXPECT_THAT(feed.added, ElementsAre(1u));
  // Centres 4.5 m apart, radii 2 and 2: disjoint circles, no link. The facing
  // endpoints are exactly snap_m apart, not closer, so no corner either.
  ASSERT_TRUE(engine.Add(2, 0, {Wall(2, {4.5, 0}, {8.5, 0})}, &feed).ok());
  EXPECT_THAT(feed.added, ElementsAre(2u));
  EXPECT_THAT(feed.updated, IsEmpty());
  EXPECT_EQ(engine.published_count(), 2u);
  // A feature whose centre lies within eta of both bridges them: 2 is absorbed into 1.
  ASSERT_TRUE(engine.Add(3, 0, {Wall(3, {1.5, 0}, {7, 0})}, &feed).ok());
  EXPECT_THAT(feed.added, IsEmpty());
  EXPECT_THAT(feed.updated, ElementsAre(1u));
  EXPECT_THAT(feed.removed, ElementsAre(2u));
  EXPECT_EQ(engine.published_count(), 1u);
  EXPECT_EQ(engine.Published()[0].member_count, 3u);
  // Something far away changes nothing published.
  ASSERT_TRUE(engine.Add(4, 0, {Wall(4, {100, 100}, {101, 100})}, &feed).ok());
  EXPECT_THAT(feed.added, ElementsAre(4u));
  EXPECT_THAT(feed.updated, IsEmpty());
}

// An L-shaped corner at (10, 0) seen twice; the fitted endpoints stop short of it.
class CornerTest : public ::testing::TestWithParam<CornerMode> {
 protected:
  void AddL(FusionEngine* engine, ChangeFeed* feed) {
    ASSERT_TRUE(engine->Add(1, 0, {Wall(1, {0, 0}, {9.8, 0})}).ok());
    ASSERT_TRUE(engine->Add(2, 0, {Wall(2, {0.1, 0}, {9.7, 0})}).ok());
    ASSERT_TRUE(engine->Add(3, 0, {Wall(3, {10, 0.2}, {10, 8})}).ok());
    ASSERT_TRUE(engine->Add(4, 0, {Wall(4, {10, 0.3}, {10, 7.9})}, feed).ok());
  }
};

TEST_P(CornerTest, EndpointsMeetAtTheCorner) {
  FusionParams params = Support(2);
  params.corner_mode = GetParam();
  FusionEngine engine(params);
  ChangeFeed feed;
  AddL(&engine, &feed);
  // The vertical wall was published now, and moved the horizontal wall's corner.
  EXPECT_THAT(feed.added, ElementsAre(3u));
  EXPECT_THAT(feed.updated, ElementsAre(1u));
  const std::vector<FusedFeature> published = engine.Published();
  ASSERT_EQ(published.size(), 2u);
  const Vec2 expected = GetParam() == CornerMode::kIntersection ? Vec2(10, 0) : Vec2(9.9, 0.1);
  const auto near_corner = [](const geometry::Segment2& s) {
    return (s.a - Vec2(10, 0)).norm() < (s.b - Vec2(10, 0)).norm() ? s.a : s.b;
  };
  ExpectNear(near_corner(published[0].segment), expected, 1e-9);
  ExpectNear(near_corner(published[1].segment), expected, 1e-9);
  // The far ends stay where the fit put them.
  const auto far_end = [](const geometry::Segment2& s) {
    return (s.a - Vec2(10, 0)).norm() < (s.b - Vec2(10, 0)).norm() ? s.b : s.a;
  };
  ExpectNear(far_end(published[0].segment), {0, 0}, 1e-9);
  ExpectNear(far_end(published[1].segment), {10, 8}, 1e-9);
}

INSTANTIATE_TEST_SUITE_P(BothModes, CornerTest,
                         ::testing::Values(CornerMode::kMidpoint, CornerMode::kIntersection),
                         [](const auto& param_info) {
                           return std::string(CornerModeName(param_info.param));
                         });

// Intersection corners without a usable intersection (near-parallel walls)
// keep each wall on its own line: the ends slide along their lines to the
// foot of their midpoint, instead of both moving to the midpoint, which
// tilted each wall by up to snap_m / 2 (issue 40: a real corridor wall drawn
// 13 cm into the corridor).
TEST(FusionEngineTest, ANearParallelCornerKeepsEachWallOnItsLine) {
  FusionParams params = Support(1);
  params.corner_mode = CornerMode::kIntersection;
  FusionEngine engine(params);
  ASSERT_TRUE(engine.Add(1, 0, {Wall(1, {0, 0}, {5, 0}), Wall(2, {5.3, 0.3}, {10, 0.3})}).ok());
  const std::vector<FusedFeature> walls = engine.Published();
  ASSERT_EQ(walls.size(), 2u);
  const auto ends = [](const FusedFeature& f) {
    return f.segment.a.x() < f.segment.b.x() ? std::make_pair(f.segment.a, f.segment.b)
                                             : std::make_pair(f.segment.b, f.segment.a);
  };
  ExpectNear(ends(walls[0]).first, {0, 0}, 1e-9);
  ExpectNear(ends(walls[0]).second, {5.15, 0}, 1e-9);
  ExpectNear(ends(walls[1]).first, {5.15, 0.3}, 1e-9);
  ExpectNear(ends(walls[1]).second, {10, 0.3}, 1e-9);
}

// Six walls end on the x axis, at A (wall 1) -0.02, B 0.3, C 0.5, D 0.95, E 1.3,
// F 1.55 (wall 6), each going off in its own direction; snap_m = 0.5. Mutual
// nearest: B-C and E-F snap (each the other's nearest), A and D stay. Greedy in
// id order: A-B, C-D, E-F. Wall 1 arrives last: before it, greedy had B-C and
// D-E, so it re-pairs a chain reaching farther than 2 * snap_m from wall 1.
TEST(CornerPairingTest, MutualAndGreedyPairDifferently) {
  const double x[6] = {-0.02, 0.3, 0.5, 0.95, 1.3, 1.55};
  const double heading_deg[6] = {180, 90, -60, 45, -100, 120};
  const auto wall = [&](int k) {
    const double t = heading_deg[k] * 3.14159265358979323846 / 180.0;
    return Wall(static_cast<FeatureId>(k + 1), {x[k], 0},
                Vec2(x[k], 0) + 8.0 * Vec2(std::cos(t), std::sin(t)));
  };
  for (CornerPairing pairing : {CornerPairing::kMutualNearest, CornerPairing::kGreedy}) {
    SCOPED_TRACE(CornerPairingName(pairing));
    FusionParams params = Support(1);
    params.corner_mode = CornerMode::kMidpoint;
    params.corner_pairing = pairing;
    FusionEngine engine(params);
    ChangeFeed feed;
    ASSERT_TRUE(engine.Add(1, 0, {wall(5), wall(4), wall(3), wall(2), wall(1)}).ok());
    ASSERT_TRUE(engine.Add(2, 0, {wall(0)}, &feed).ok());
    EXPECT_THAT(feed.added, ElementsAre(1u));
    const std::vector<FusedFeature> walls = engine.Published();
    ASSERT_EQ(walls.size(), 6u);
    // The end of each wall on the x axis (the fit may orient a segment either way).
    std::vector<double> ends;
    for (const FusedFeature& f : walls) {
      const Vec2& e =
          std::abs(f.segment.a.y()) < std::abs(f.segment.b.y()) ? f.segment.a : f.segment.b;
      EXPECT_NEAR(e.y(), 0.0, 1e-9);
      ends.push_back(e.x());
    }
    const std::vector<double> expected =
        pairing == CornerPairing::kMutualNearest
            ? std::vector<double>{-0.02, 0.4, 0.4, 0.95, 1.425, 1.425}
            : std::vector<double>{0.14, 0.14, 0.725, 0.725, 1.425, 1.425};
    for (size_t k = 0; k < 6; ++k) EXPECT_NEAR(ends[k], expected[k], 1e-9) << "wall " << k + 1;
    if (pairing == CornerPairing::kMutualNearest) {
      EXPECT_THAT(feed.updated, IsEmpty());  // wall 1 changed no pair
    } else {
      EXPECT_THAT(feed.updated, ElementsAre(2u, 3u, 4u, 5u, 6u));  // B-C, D-E broken up
    }
  }
}

TEST(FusionEngineTest, CreateRefusesInvalidParams) {
  FusionParams params;
  params.gamma = 2.0;
  EXPECT_EQ(FusionEngine::Create(params).status().code(), StatusCode::kInvalidArgument);
  EXPECT_TRUE(FusionEngine::Create(FusionParams()).ok());
}

// A quarter circle of radius 5 m seen by `scans` observations as 0.5 m chords,
// each scan's chords shifted by a fraction of a chord so that they chain.
void AddArc(FusionEngine* engine, int scans, FeatureId* next_id) {
  constexpr double kRadiusM = 5.0;
  constexpr double kStepRad = 0.5 / kRadiusM;
  for (int s = 0; s < scans; ++s) {
    std::vector<GroundFeature> features;
    for (double angle = kStepRad * s / scans; angle + kStepRad <= 1.5707963; angle += kStepRad) {
      features.push_back(
          Wall((*next_id)++, kRadiusM * Vec2(std::cos(angle), std::sin(angle)),
               kRadiusM * Vec2(std::cos(angle + kStepRad), std::sin(angle + kStepRad))));
    }
    ASSERT_TRUE(engine->Add(100 + s, 0, features).ok());
  }
}

TEST(FusionEngineTest, ChainGuardCutsACurvedWallIntoPieces) {
  FusionParams off = Support(2);
  off.chain_max_rms_m = 0.0;
  FusionEngine chained(off);
  FeatureId id = 1;
  AddArc(&chained, 4, &id);
  // The paper's method: one cluster, a straight chord far from the wall.
  ASSERT_EQ(chained.published_count(), 1u);
  EXPECT_GT(geometry::PointSegmentDistance(Vec2(5.0, 5.0).normalized() * 5.0,
                                           chained.Published()[0].fitted),
            0.4);

  FusionEngine guarded(Support(2));  // the default guard
  id = 1;
  AddArc(&guarded, 4, &id);
  const std::vector<FusedFeature> pieces = guarded.Published();
  ASSERT_GE(pieces.size(), 3u);
  uint32_t members = 0;
  for (const FusedFeature& f : pieces) {
    members += f.member_count;
    // Every piece follows the wall: its ends and middle within 12 cm of the
    // circle (the guard bounds the RMS residual by 5 cm, not the largest one).
    EXPECT_NEAR(f.fitted.a.norm(), 5.0, 0.12);
    EXPECT_NEAR(f.fitted.b.norm(), 5.0, 0.12);
    EXPECT_NEAR(f.fitted.midpoint().norm(), 5.0, 0.12);
  }
  EXPECT_EQ(members, guarded.feature_count());
  EXPECT_EQ(guarded.cluster_count(), pieces.size());
  // Named by the smallest member id: the piece holding feature 1 is called 1.
  EXPECT_EQ(pieces.front().id, 1u);
}

// Bounded mode's cost caps (params.h; issue 46): what one observation can
// cost stays bounded whatever came before.
FusionParams Capped(uint32_t max_component_nodes) {
  FusionParams p;  // bounded, the default
  p.min_support = 2;
  p.max_component_nodes = max_component_nodes;
  return p;
}

TEST(FusionEngineCapsTest, AComponentTheGuardRegroupsStopsAtTheCap) {
  FusionEngine uncapped(Capped(1u << 20));
  FeatureId id = 1;
  AddArc(&uncapped, 4, &id);
  ASSERT_GT(uncapped.largest_component_nodes(), 16u) << "the arc must chain past the cap";

  FusionEngine capped(Capped(16));
  id = 1;
  AddArc(&capped, 4, &id);
  EXPECT_LE(capped.largest_component_nodes(), 16u);
  EXPECT_EQ(capped.node_count(), uncapped.node_count()) << "nothing is dropped";
  // Still the wall: every piece follows the circle (see the guard's test).
  ASSERT_GE(capped.published_count(), 3u);
  for (const FusedFeature& f : capped.Published()) {
    EXPECT_NEAR(f.fitted.a.norm(), 5.0, 0.12);
    EXPECT_NEAR(f.fitted.b.norm(), 5.0, 0.12);
    EXPECT_NEAR(f.fitted.midpoint().norm(), 5.0, 0.12);
  }
}

TEST(FusionEngineCapsTest, AStraightWallGrowsPastTheCap) {
  // The guard never regroups a straight wall, so the cap does not split it.
  FusionEngine engine(Capped(16));
  for (int s = 0; s < 30; ++s) {
    const double shift = 0.03 * s;  // no two alike: every feature a node
    ASSERT_TRUE(
        engine.Add(100 + s, 0, {Wall(s + 1, Vec2(shift, 0.0), Vec2(4.0 + shift, 0.0))}).ok());
  }
  EXPECT_EQ(engine.node_count(), 30u);
  EXPECT_EQ(engine.largest_component_nodes(), 30u);
  EXPECT_EQ(engine.published_count(), 1u);
}

TEST(FusionEngineCapsTest, NoWallGrowsPastMaxWallLength) {
  FusionParams p = Capped(256);
  p.max_wall_length_m = 10.0;
  // The clusters; wall consolidation may still publish pieces on one line as
  // one feature (docs/reliability.md says what that costs).
  p.consolidate = false;
  FusionEngine engine(p);
  // A 4 m line sent again and again, 1 m further each time: one straight
  // chain, cut where it would pass 10 m.
  for (int s = 0; s < 30; ++s) {
    ASSERT_TRUE(engine.Add(100 + s, 0, {Wall(s + 1, Vec2(s, 0.0), Vec2(s + 4.0, 0.0))}).ok());
  }
  EXPECT_GT(engine.cluster_count(), 3u);
  for (const FusedFeature& f : engine.Published()) EXPECT_LE(f.fitted.length(), 10.0 + 1e-9);
  // A longer feature is refused, naming the limit.
  const Status s = engine.Add(200, 0, {Wall(1000, Vec2(0.0, 5.0), Vec2(10.5, 5.0))});
  EXPECT_EQ(s.code(), StatusCode::kInvalidArgument);
  EXPECT_THAT(s.message(), ::testing::HasSubstr("max_wall_length_m"));
}

TEST(FusionEngineCapsTest, ALinkSearchComparesWithAtMostTheCandidateCap) {
  // 30 views of one short wall, all filed in one 1 m cell of the link index.
  const auto feed = [](FusionEngine* engine) {
    for (int s = 0; s < 30; ++s) {
      const double shift = 0.01 * s;
      ASSERT_TRUE(
          engine->Add(100 + s, 0, {Wall(s + 1, Vec2(0.2 + shift, 0.5), Vec2(0.8 + shift, 0.5))})
              .ok());
    }
  };
  FusionEngine open(Capped(256));
  feed(&open);
  EXPECT_EQ(open.cluster_count(), 1u);

  FusionParams p = Capped(256);
  p.max_link_candidates = 16;
  FusionEngine capped(p);
  feed(&capped);
  // Once the cell holds more than 16, a new feature compares with none of
  // them (whole cells or nothing) and starts a cluster of its own.
  EXPECT_EQ(capped.node_count(), 30u);
  EXPECT_EQ(capped.largest_component_nodes(), 17u);
  EXPECT_EQ(capped.cluster_count(), 1u + 13u);
}

// Four observations, one 1.5 m chord each, 0.6 m apart along a wall curved
// with radius 8 m: they chain into one cluster of support 4 that bends too
// much for one line.
void AddFourChords(FusionEngine* engine) {
  constexpr double kRadiusM = 8.0;
  for (int s = 0; s < 4; ++s) {
    const double a0 = 0.6 * s / kRadiusM, a1 = a0 + 1.5 / kRadiusM;
    const GroundFeature f = Wall(s + 1, kRadiusM * Vec2(std::cos(a0), std::sin(a0)),
                                 kRadiusM * Vec2(std::cos(a1), std::sin(a1)));
    ASSERT_TRUE(engine->Add(100 + s, 0, {f}).ok());
  }
}

TEST(FusionEngineTest, ChainGuardNeverCutsOffAPieceBelowMinSupport) {
  // With min_support 2 the guard cuts the chain (so it is a chain).
  FusionEngine low(Support(2));
  AddFourChords(&low);
  ASSERT_GE(low.published_count(), 2u);
  // With min_support 3 every cut leaves a piece of support < 3: the cluster
  // stays whole and is published, as without the guard.
  FusionEngine guarded(Support(3));
  AddFourChords(&guarded);
  FusionParams off = Support(3);
  off.chain_max_rms_m = 0.0;
  FusionEngine plain(off);
  AddFourChords(&plain);
  ASSERT_EQ(plain.published_count(), 1u);
  ASSERT_EQ(guarded.published_count(), 1u);
  EXPECT_EQ(guarded.Published()[0].support, 4u);
  EXPECT_EQ(guarded.Published()[0].fitted.a, plain.Published()[0].fitted.a);
}

TEST(FusionEngineTest, ChainGuardKeepsAStraightWallWhole) {
  FusionParams off = Support(2);
  off.chain_max_rms_m = 0.0;
  FusionEngine plain(off);
  FusionEngine guarded(Support(2));
  for (int s = 0; s < 6; ++s) {
    // 3 cm offsets from scan to scan: the fit's RMS stays below 5 cm.
    const double y = 0.03 * (s % 3);
    const GroundFeature f = Wall(10 + s, {0.5 * s, y}, {6.0 + 0.5 * s, y});
    ASSERT_TRUE(plain.Add(s, 0, {f}).ok());
    ChangeFeed feed;
    ASSERT_TRUE(guarded.Add(s, 0, {f}, &feed).ok());
    EXPECT_THAT(feed.removed, IsEmpty());
  }
  ASSERT_EQ(guarded.published_count(), 1u);
  EXPECT_EQ(guarded.Published()[0].fitted.a, plain.Published()[0].fitted.a);
  EXPECT_EQ(guarded.Published()[0].fitted.b, plain.Published()[0].fitted.b);
}

TEST(FusionEngineTest, ChainGuardFeedFollowsTheNamesOfPieces) {
  // Two parallel walls 40 cm apart, linked (eta = 0.5) but published apart by
  // the guard. Then feature 1 close to wall 5: the piece {1, 5} is named 1, so
  // 5 is removed and 1 added, while the untouched piece 3 is not reported.
  FusionParams params = Support(1);
  params.eta_m = 0.5;
  params.consolidate = false;  // with eta 0.5, consolidation would publish them as one wall
  FusionEngine engine(params);
  ASSERT_TRUE(engine.Add(1, 0, {Wall(5, {0, 0}, {4, 0})}).ok());
  ChangeFeed feed;
  ASSERT_TRUE(engine.Add(2, 0, {Wall(3, {-1, 0.4}, {3, 0.4})}, &feed).ok());
  EXPECT_EQ(EngineInspector::Partition(engine), (std::vector<std::vector<FeatureId>>{{3}, {5}}));
  EXPECT_THAT(feed.added, ElementsAre(3u));
  EXPECT_THAT(feed.removed, IsEmpty());
  ASSERT_TRUE(engine.Add(3, 0, {Wall(1, {0.5, 0.02}, {4.5, 0.02})}, &feed).ok());
  EXPECT_EQ(EngineInspector::Partition(engine), (std::vector<std::vector<FeatureId>>{{1, 5}, {3}}));
  EXPECT_THAT(feed.added, ElementsAre(1u));
  EXPECT_THAT(feed.removed, ElementsAre(5u));
  EXPECT_THAT(feed.updated, IsEmpty());
  EXPECT_EQ(engine.cluster_count(), 2u);
  ASSERT_TRUE(engine.Get(1).has_value());
  EXPECT_EQ(engine.Get(1)->member_count, 2u);
  EXPECT_FALSE(engine.Get(5).has_value());
}

}  // namespace
}  // namespace mapd::fusion
