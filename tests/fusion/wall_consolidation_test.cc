// Wall consolidation (pieces of one wall published as one feature, gaps wider
// than wall_gap kept) and its interplay with corner snapping.
#include "fusion/wall_consolidation.h"

#include <gtest/gtest.h>

#include "fusion/engine.h"

namespace mapd::fusion {
namespace {

using geometry::Segment2;
using geometry::Vec2;

// The demo floor's wall y = 0, seen from its two ends by three observations
// each: (0,0)-(7.2,0) and (7,0)-(20,0). Criterion 3 never links the two
// pieces (each centre is metres from the other segment).
void AddTwoEnds(FusionEngine* engine, double second_start_x) {
  FeatureId id = 1;
  for (ObservationId o = 1; o <= 3; ++o) {
    GroundFeature f;
    f.id = id++;
    f.segment = {Vec2(0.0, 0.001 * o), Vec2(7.2, 0.001 * o)};
    ASSERT_TRUE(engine->Add(o, 0, {f}).ok());
  }
  for (ObservationId o = 4; o <= 6; ++o) {
    GroundFeature f;
    f.id = id++;
    f.segment = {Vec2(second_start_x, -0.001 * o), Vec2(20.0, -0.001 * o)};
    ASSERT_TRUE(engine->Add(o, 0, {f}).ok());
  }
}

FusionParams Params(bool consolidate) {
  FusionParams p;
  p.consolidate = consolidate;
  return p;
}

TEST(WallConsolidationTest, PiecesSeenFromTheTwoEndsOfAWallAreOneFeature) {
  FusionEngine paper(Params(false));
  AddTwoEnds(&paper, 7.0);
  ASSERT_EQ(paper.published_count(), 2u) << "the paper's method publishes two overlapping pieces";

  FusionEngine engine(Params(true));
  AddTwoEnds(&engine, 7.0);
  ASSERT_EQ(engine.published_count(), 1u);
  const FusedFeature wall = engine.Published()[0];
  EXPECT_EQ(wall.id, 1u);  // the smallest member id
  EXPECT_EQ(wall.support, 6u);
  EXPECT_EQ(wall.member_count, 6u);
  EXPECT_NEAR(std::min(wall.segment.a.x(), wall.segment.b.x()), 0.0, 1e-6);
  EXPECT_NEAR(std::max(wall.segment.a.x(), wall.segment.b.x()), 20.0, 1e-6);
  // The other piece's name is not a feature of its own any more.
  EXPECT_FALSE(engine.Get(4).has_value());
}

TEST(WallConsolidationTest, AGapWiderThanWallGapKeepsTwoFeatures) {
  FusionEngine engine(Params(true));
  AddTwoEnds(&engine, 7.2 + 1.0);  // a 1 m passage between the pieces
  EXPECT_EQ(engine.published_count(), 2u);
  FusionParams wide = Params(true);
  wide.wall_gap_m = 1.5;
  FusionEngine bridged(wide);
  AddTwoEnds(&bridged, 7.2 + 1.0);
  EXPECT_EQ(bridged.published_count(), 1u);
}

TEST(WallConsolidationTest, TheFeedReportsTheJoin) {
  FusionEngine engine(Params(true));
  FeatureId id = 1;
  for (ObservationId o = 1; o <= 3; ++o) {
    GroundFeature f;
    f.id = id++;
    f.segment = {Vec2(0.0, 0.0), Vec2(7.2, 0.0)};
    ASSERT_TRUE(engine.Add(o, 0, {f}).ok());
  }
  ChangeFeed feed;
  for (ObservationId o = 4; o <= 6; ++o) {
    GroundFeature f;
    f.id = 100 + o;
    f.segment = {Vec2(7.0, 0.0), Vec2(20.0, 0.0)};
    ASSERT_TRUE(engine.Add(o, 0, {f}, &feed).ok());
  }
  // The third observation of the second piece publishes it, and it joins wall 1.
  EXPECT_TRUE(feed.added.empty());
  EXPECT_EQ(feed.updated, std::vector<ClusterId>{1});
  EXPECT_TRUE(feed.removed.empty());
}

// Two short crossing features whose ends pair at both ends: corner snapping
// leaves them as they are instead of publishing one segment twice.
TEST(CornerSnapTest, FeaturesPairedAtBothEndsAreNotSnappedOntoEachOther) {
  FusionParams p;
  p.min_support = 1;
  FusionEngine engine(p);
  GroundFeature a, b;
  a.id = 1;
  a.segment = {Vec2(0, 0), Vec2(1, 0.5)};
  b.id = 2;
  b.segment = {Vec2(0, 0.3), Vec2(1, 0.1)};
  ASSERT_TRUE(engine.Add(1, 0, {a}).ok());
  ASSERT_TRUE(engine.Add(2, 0, {b}).ok());
  const std::vector<FusedFeature> published = engine.Published();
  ASSERT_EQ(published.size(), 2u);
  for (const FusedFeature& f : published) {
    EXPECT_EQ(f.segment.a, f.fitted.a);
    EXPECT_EQ(f.segment.b, f.fitted.b);
  }
}

TEST(OnOneWallTest, StatesTheRelation) {
  FusionParams p;  // delta 5 deg, wall_offset_m 0.1 m, wall_gap_m 0.3 m
  const Segment2 long_wall{Vec2(0, 0), Vec2(10, 0)};
  EXPECT_TRUE(OnOneWall(long_wall, 1, {Vec2(9, 0.05), Vec2(14, 0.05)}, 2, p));  // overlap
  EXPECT_TRUE(OnOneWall(long_wall, 1, {Vec2(10.25, 0), Vec2(14, 0)}, 2, p));    // gap 0.25
  EXPECT_FALSE(OnOneWall(long_wall, 1, {Vec2(10.5, 0), Vec2(14, 0)}, 2, p));    // gap 0.5
  EXPECT_FALSE(OnOneWall(long_wall, 1, {Vec2(5, 0.2), Vec2(14, 0.2)}, 2, p));  // 0.2 m off: a shelf
  EXPECT_FALSE(OnOneWall(long_wall, 1, {Vec2(9, 0), Vec2(12, 0.5)}, 2, p));    // 9.5 deg
  // Symmetric, whichever is passed first.
  EXPECT_TRUE(OnOneWall({Vec2(9, 0.05), Vec2(14, 0.05)}, 2, long_wall, 1, p));
  // A short piece wholly inside the eta band along L is one with it, whatever
  // its direction (a corner fragment: 0.78 m, 6 deg off the wall).
  EXPECT_TRUE(OnOneWall(long_wall, 1, {Vec2(0.04, 0.04), Vec2(0.81, -0.04)}, 2, p));
  EXPECT_FALSE(
      OnOneWall(long_wall, 1, {Vec2(-0.5, 0.04), Vec2(0.3, -0.04)}, 2, p));  // sticks out, 6 deg
  // Near-identical short features are one, whatever their directions.
  EXPECT_TRUE(
      OnOneWall({Vec2(0, 0), Vec2(0.4, 0)}, 1, {Vec2(0.05, 0.05), Vec2(0.35, -0.05)}, 2, p));
}

}  // namespace
}  // namespace mapd::fusion
