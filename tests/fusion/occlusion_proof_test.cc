// Proofs of occlusion (fusion/occlusion_proof.h) and their use in wall
// consolidation: a short gap joins only where an observation saw something
// in front of it (FusionParams::wall_proof_gap_m, docs/algorithms.md A.11).
#include "fusion/occlusion_proof.h"

#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "fusion/engine.h"
#include "fusion/evidence_scenes.h"
#include "fusion/params.h"

namespace mapd::fusion {
namespace {

using geometry::Segment2;
using geometry::Vec2;

// The stretch's x extent on y = 0.
std::pair<double, double> Extent(const Segment2& s) {
  EXPECT_NEAR(s.a.y(), 0.0, 1e-9);
  EXPECT_NEAR(s.b.y(), 0.0, 1e-9);
  return {std::min(s.a.x(), s.b.x()), std::max(s.a.x(), s.b.x())};
}

TEST(OccludedStretchesTest, AnOccludersShadowOnTheGapIsProven) {
  const FusionParams params;
  const Vec2 sensor(6.0, -6.0);
  const Segment2 left{Vec2(0.0, 0.0), Vec2(5.0, 0.0)}, right{Vec2(7.0, 0.0), Vec2(12.0, 0.0)};
  // Rays from (6, -6) through (5.5, -2) and (6.5, -2) meet y = 0 at 5.25 and 6.75.
  const Segment2 cabinet{Vec2(5.5, -2.0), Vec2(6.5, -2.0)};
  const std::vector<Segment2> proven = OccludedStretches(sensor, {left, cabinet, right}, params);
  ASSERT_EQ(proven.size(), 1u);
  EXPECT_NEAR(Extent(proven[0]).first, 5.25, 1e-9);
  EXPECT_NEAR(Extent(proven[0]).second, 6.75, 1e-9);

  // A wider occluder's shadow is clipped to the gap.
  const Segment2 wide{Vec2(4.0, -2.0), Vec2(8.0, -2.0)};
  const std::vector<Segment2> clipped = OccludedStretches(sensor, {left, wide, right}, params);
  ASSERT_EQ(clipped.size(), 1u);
  EXPECT_NEAR(Extent(clipped[0]).first, 5.0, 1e-9);
  EXPECT_NEAR(Extent(clipped[0]).second, 7.0, 1e-9);
}

TEST(OccludedStretchesTest, NothingInFrontProvesNothing) {
  const FusionParams params;
  const Vec2 sensor(6.0, -6.0);
  const Segment2 left{Vec2(0.0, 0.0), Vec2(5.0, 0.0)}, right{Vec2(7.0, 0.0), Vec2(12.0, 0.0)};
  EXPECT_TRUE(OccludedStretches(sensor, {left, right}, params).empty()) << "no occluder";
  const Segment2 behind{Vec2(5.5, 2.0), Vec2(6.5, 2.0)};  // seen through the gap
  EXPECT_TRUE(OccludedStretches(sensor, {left, behind, right}, params).empty());
  const Segment2 aside{Vec2(9.0, -2.0), Vec2(10.0, -2.0)};  // in front of a piece, not the gap
  EXPECT_TRUE(OccludedStretches(sensor, {left, aside, right}, params).empty());
  // Pieces not on one line (20 cm apart laterally) have no gap between them.
  const Segment2 offset_right{Vec2(7.0, 0.2), Vec2(12.0, 0.2)};
  const Segment2 cabinet{Vec2(5.5, -2.0), Vec2(6.5, -2.0)};
  EXPECT_TRUE(OccludedStretches(sensor, {left, cabinet, offset_right}, params).empty());
  // A gap within wall_gap_m needs no proof and gets none.
  const Segment2 near_right{Vec2(5.2, 0.0), Vec2(12.0, 0.0)};
  EXPECT_TRUE(OccludedStretches(sensor, {left, cabinet, near_right}, params).empty());
}

// A corridor wall y = 0 in two pieces, x in [0, 5] and [6.5, 12], with a 1.5 m
// doorway between them, seen by 4 views from the corridor. Through the
// doorway the laser saw only clutter, which gave no segment: no visibility
// triangle crosses the doorway. With `cabinet`, a cabinet stands in front of
// the gap in every view instead.
std::vector<Obs> Doorway(bool cabinet) {
  SceneBuilder scene;
  for (int k = 0; k < 4; ++k) {
    const double jitter = 0.002 * k;
    std::vector<Segment2> segments = {{Vec2(0.0, jitter), Vec2(5.0, jitter)},
                                      {Vec2(6.5, -jitter), Vec2(12.0, -jitter)}};
    if (cabinet) segments.push_back({Vec2(5.2, -1.5 + jitter), Vec2(6.3, -1.5 + jitter)});
    scene.Add(Vec2(5.5 + 0.3 * k, -3.0), segments);
  }
  return scene.Take();
}

TEST(OcclusionProofTest, ADoorwaySeenThroughToClutterStaysOpen) {
  FusionParams params;
  params.mode = FusionMode::kExact;
  FusionEngine engine(params);
  Feed(&engine, Doorway(false));
  EXPECT_EQ(OnWallLine(engine).size(), 2u) << "nothing proved the 1.5 m gap occluded";

  FusionParams unproven = params;  // the rule before issue 40: unseen means occluded
  unproven.wall_proof_gap_m = 0.0;
  FusionEngine old_rule(unproven);
  Feed(&old_rule, Doorway(false));
  EXPECT_EQ(OnWallLine(old_rule).size(), 1u);
}

TEST(OcclusionProofTest, AGapBehindAnOccluderJoins) {
  FusionParams params;
  params.mode = FusionMode::kExact;
  FusionEngine engine(params);
  Feed(&engine, Doorway(true));
  const auto wall = OnWallLine(engine);
  ASSERT_EQ(wall.size(), 1u);
  EXPECT_NEAR(wall[0].first, 0.0, 0.05);
  EXPECT_NEAR(wall[0].second, 12.0, 0.05);
}

TEST(OcclusionProofTest, AProofArrivingLaterJoinsAndSnapshotsKeepIt) {
  // The doorway first, then the cabinet's views: the wall joins when the
  // proof arrives, in a live engine and in one restored from a snapshot taken
  // before it.
  std::vector<Obs> observations = Doorway(false);
  std::vector<Obs> proof = Doorway(true);
  for (Obs& o : proof) o.id += 100;
  for (Obs& o : proof) {
    for (GroundFeature& f : o.features) f.id += 1000;
  }
  FusionParams params;
  params.mode = FusionMode::kBounded;
  FusionEngine live(params);
  Feed(&live, observations);
  EXPECT_EQ(OnWallLine(live).size(), 2u);
  std::string state;
  ASSERT_TRUE(live.SaveState(&state).ok());
  Feed(&live, {proof[0]});
  std::string proven_state;
  ASSERT_TRUE(live.SaveState(&proven_state).ok());
  auto restored = FusionEngine::LoadState(params, proven_state);
  ASSERT_TRUE(restored.ok()) << restored.status().ToString();
  std::string again;
  ASSERT_TRUE((*restored)->SaveState(&again).ok());
  EXPECT_EQ(again, proven_state) << "the proofs are in the snapshot";
  auto before_proof = FusionEngine::LoadState(params, state);
  ASSERT_TRUE(before_proof.ok());
  Feed(before_proof->get(), {proof[0]});
  for (size_t k = 1; k < proof.size(); ++k) {
    Feed(&live, {proof[k]});
    Feed(restored->get(), {proof[k]});
    Feed(before_proof->get(), {proof[k]});
  }
  EXPECT_EQ(OnWallLine(live).size(), 1u);
  EXPECT_EQ(Describe((*restored)->Published()), Describe(live.Published()));
  EXPECT_EQ(Describe((*before_proof)->Published()), Describe(live.Published()));
  // Another proof setting is refused (the params key records it).
  FusionParams other = params;
  other.wall_proof_gap_m = 2.0;
  EXPECT_FALSE(FusionEngine::LoadState(other, proven_state).ok());
}

TEST(OcclusionProofTest, ParamsAreValidated) {
  FusionParams p;
  p.wall_proof_gap_m = -1.0;
  EXPECT_FALSE(p.Validate().ok());
  p.wall_proof_gap_m = 1001.0;
  EXPECT_FALSE(p.Validate().ok());
  p.wall_proof_gap_m = 0.0;
  EXPECT_TRUE(p.Validate().ok());
}

}  // namespace
}  // namespace mapd::fusion
