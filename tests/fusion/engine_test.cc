#include "fusion/engine.h"

#include <limits>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "fusion/engine_inspector.h"

namespace mapd::fusion {
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

FusionParams Support(uint32_t min_support) {
  FusionParams p;
  p.min_support = min_support;
  return p;
}

void ExpectNear(const Vec2& actual, const Vec2& expected, double tolerance_m) {
  EXPECT_LE((actual - expected).norm(), tolerance_m)
      << actual.transpose() << " vs " << expected.transpose();
}

TEST(FusionEngineTest, TwoObservationsOfOneWallFuse) {
  FusionEngine engine(Support(2));
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

TEST(FusionEngineTest, CreateRefusesInvalidParams) {
  FusionParams params;
  params.gamma = 2.0;
  EXPECT_EQ(FusionEngine::Create(params).status().code(), StatusCode::kInvalidArgument);
  EXPECT_TRUE(FusionEngine::Create(FusionParams()).ok());
}

}  // namespace
}  // namespace mapd::fusion
