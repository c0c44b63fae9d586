// Free-space evidence (fusion/free_space.h) and its use in wall consolidation
// (wall_occluded_gap_m, docs/algorithms.md A.11).
#include "fusion/free_space.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <string>
#include <vector>

#include "fusion/engine.h"
#include "fusion/evidence_scenes.h"
#include "fusion/params.h"

namespace mapd::fusion {
namespace {

using geometry::Segment2;
using geometry::Vec2;

constexpr double kRangeM = 80.0;  // FusionParams::evidence_range_m's default

TEST(FreeSpaceGridTest, MarksTheTriangleInsideItsMargins) {
  FreeSpaceGrid grid(2, kRangeM);
  const Vec2 origin(0.0, -10.0);
  const Segment2 wall{Vec2(-5.0, 0.0), Vec2(5.0, 0.0)};
  grid.AddView(origin, wall);
  EXPECT_FALSE(grid.IsFree(Vec2(0.0, -5.0))) << "one view is below min_count 2";
  EXPECT_EQ(grid.TakeNewlyFree().size(), 0u);
  grid.AddView(origin, wall);
  EXPECT_TRUE(grid.IsFree(Vec2(0.0, -5.0)));
  EXPECT_TRUE(grid.IsFree(Vec2(-4.0, -1.0)));
  EXPECT_FALSE(grid.IsFree(Vec2(0.0, 0.05))) << "the wall's own line";
  EXPECT_FALSE(grid.IsFree(Vec2(0.0, -0.2))) << "within the segment margin";
  EXPECT_FALSE(grid.IsFree(Vec2(0.0, 3.0))) << "behind the wall";
  EXPECT_FALSE(grid.IsFree(Vec2(6.0, -5.0))) << "beside the triangle";
  EXPECT_FALSE(grid.IsFree(Vec2(2.6, -5.0))) << "outside the ray (x = 2.5 at y = -5)";
  // The margins, on cell centres (cells of 0.25 m, centres at odd multiples
  // of 0.125) inside the triangle: the ray to (5, 0) crosses y = -4.875 at
  // x = 2.5625 and runs at 63.4 deg, so a centre dx left of it lies
  // 0.894 dx from it.
  EXPECT_TRUE(grid.IsFree(Vec2(2.375, -4.875))) << "0.17 m from the ray at 5.7 m range";
  EXPECT_FALSE(grid.IsFree(Vec2(2.625, -4.875))) << "beyond the ray";
  EXPECT_FALSE(grid.IsFree(Vec2(0.125, -0.375))) << "0.375 m before the segment: within 0.4 m";
  EXPECT_TRUE(grid.IsFree(Vec2(0.125, -0.625))) << "0.625 m before the segment";
  const std::vector<uint64_t> newly = grid.TakeNewlyFree();
  EXPECT_GT(newly.size(), 100u);
  EXPECT_TRUE(std::is_sorted(newly.begin(), newly.end()));
  for (uint64_t cell : newly) EXPECT_TRUE(grid.IsFree(FreeSpaceGrid::CellCentre(cell)));
  EXPECT_TRUE(grid.TakeNewlyFree().empty());
}

// The rays are eroded by 0.005 m per metre of range: near the sensor (where
// the robot stood) a cell close to the ray is free, far along it one is not,
// so angular pose noise does not carry a ray into a corner's wall.
TEST(FreeSpaceGridTest, TheRaysErosionGrowsWithRange) {
  FreeSpaceGrid grid(1, kRangeM);
  grid.AddView(Vec2(0.0, -40.0), {Vec2(-5.0, 0.0), Vec2(5.0, 0.0)});
  // Cell centres 0.0465 m inside the ray to (5, 0), at ranges 7.4 m and 9.4 m.
  EXPECT_TRUE(grid.IsFree(Vec2(0.875, -32.625))) << "erosion 0.037 m at 7.4 m";
  EXPECT_FALSE(grid.IsFree(Vec2(1.125, -30.625))) << "erosion 0.047 m at 9.4 m";
  // 0.14 m inside the ray at 38.4 m range: within its 0.19 m.
  EXPECT_FALSE(grid.IsFree(Vec2(4.625, -1.875)));
  EXPECT_TRUE(grid.IsFree(Vec2(0.125, -38.625))) << "0.047 m inside, 1.4 m from the sensor";
}

// A valid but absurd view, a 2 km wall 1 km from the sensor, writes only the
// cells within the evidence range (issue 46: unclipped it was ~3e7 cells).
TEST(FreeSpaceGridTest, AViewIsClippedToTheEvidenceRange) {
  FreeSpaceGrid grid(1, 20.0);
  const Vec2 origin(3.0, 4.0);
  grid.AddView(origin, {Vec2(-1000.0, 1004.0), Vec2(1000.0, 1004.0)});
  EXPECT_TRUE(grid.IsFree(origin + Vec2(0.0, 10.0))) << "inside the range";
  EXPECT_TRUE(grid.IsFree(origin + Vec2(-15.0, 19.0))) << "inside the square";
  EXPECT_FALSE(grid.IsFree(origin + Vec2(0.0, 21.0))) << "beyond the range";
  EXPECT_FALSE(grid.IsFree(origin + Vec2(500.0, 900.0)));
  // (2 * 20 m / 0.25 m + 1)^2 cells touch at most 36 tiles of 32 x 32.
  EXPECT_LE(grid.tile_count(), 36u);
  const std::vector<uint64_t> newly = grid.TakeNewlyFree();
  EXPECT_GT(newly.size(), 1000u);
  EXPECT_LE(newly.size(), 161u * 161u);
  for (uint64_t cell : newly) {
    const Vec2 c = FreeSpaceGrid::CellCentre(cell) - origin;
    EXPECT_LE(c.cwiseAbs().maxCoeff(), 20.0) << c.transpose();
  }
}

TEST(FreeSpaceGridTest, AGrazingViewMarksNothingOnItsLine) {
  FreeSpaceGrid grid(1, kRangeM);
  // The sensor almost on the wall's line: the triangle is a sliver.
  for (int k = 0; k < 5; ++k) grid.AddView(Vec2(40.0, 0.05), {Vec2(0.0, 0.0), Vec2(20.0, 0.0)});
  for (double x = -5.0; x <= 45.0; x += 0.1) EXPECT_FALSE(grid.IsFree(Vec2(x, 0.0))) << x;
}

// A street scene: a wall y = 0 seen as two pieces, x in [0, 10] and [16, 26],
// from sensors at y = -10; the 6 m between them either behind a fence
// (y = -3, x in [11, 15]: no ray reaches it) or open (seen through to a back
// wall at y = 10).
std::vector<Obs> Street(bool fence, bool open_gap) {
  SceneBuilder scene;
  const auto add = [&](Vec2 origin, std::vector<Segment2> segments) {
    scene.Add(origin, segments);
  };
  for (int k = 0; k < 4; ++k) {
    const double jitter = 0.002 * k;
    add(Vec2(5.0 + k, -10.0), {{Vec2(0.0, jitter), Vec2(10.0, jitter)}});
    add(Vec2(21.0 - k, -10.0), {{Vec2(16.0, -jitter), Vec2(26.0, -jitter)}});
    if (fence) add(Vec2(13.0 - k, -10.0), {{Vec2(11.0, -3.0 + jitter), Vec2(15.0, -3.0 + jitter)}});
    if (open_gap)
      add(Vec2(13.0 + k, -10.0), {{Vec2(8.0, 10.0 + jitter), Vec2(18.0, 10.0 + jitter)}});
  }
  return scene.Take();
}

FusionParams WithEvidence(double occluded_gap_m, FusionMode mode = FusionMode::kExact) {
  FusionParams p;
  p.mode = mode;
  p.wall_occluded_gap_m = occluded_gap_m;
  p.wall_free_min_count = 2;  // the street shows each opening to four views
  return p;
}

// AddView skips strips of rows in which every cell it could cover is
// saturated and unwatched: the grid, its newly free cells and its watched
// passes must be those of a grid that visits every row. A robot revisiting
// a small block from many poses, far and short segments among the views
// (erosion turns their triangles over), watches switched on and off.
// The tile table (open addressing) through its growth: thousands of tiles,
// negative and far-off indices, each found again, and none invented.
TEST(FreeSpaceGridTest, EveryTileIsFoundAgainAfterTheTableGrows) {
  constexpr double kTileM = FreeSpaceGrid::kCellM * FreeSpaceGrid::kTileCells;
  FreeSpaceGrid grid(1, kRangeM);
  std::mt19937 rng(7);
  std::uniform_int_distribution<int> cell(0, FreeSpaceGrid::kTileCells - 1);
  std::vector<Vec2> marked, unmarked;
  for (int tx = -45; tx <= 45; ++tx) {
    for (int ty = -45; ty <= 45; ++ty) {
      // Far-off tiles too: keys whose high bits differ, not only the low ones.
      const double far = (tx + ty) % 11 == 0 ? 1e5 : 0.0;
      const Vec2 origin(tx * kTileM + far, ty * kTileM - far);
      const int cx = cell(rng), cy = cell(rng);
      const auto at = [&](int x, int y) -> Vec2 {
        return origin + FreeSpaceGrid::kCellM * Vec2(x + 0.5, y + 0.5);
      };
      marked.push_back(at(cx, cy));
      unmarked.push_back(at((cx + 1) % FreeSpaceGrid::kTileCells, cy));
      grid.AddLine(Segment2{marked.back(), marked.back()});
    }
  }
  ASSERT_EQ(grid.tile_count(), marked.size());
  for (size_t i = 0; i < marked.size(); ++i) {
    ASSERT_TRUE(grid.IsFree(marked[i])) << i;
    ASSERT_FALSE(grid.IsFree(unmarked[i])) << i;
  }
  EXPECT_FALSE(grid.IsFree(Vec2(-3e5, 2e5)));  // no tile there
  const auto tiles = grid.SortedTiles();
  ASSERT_EQ(tiles.size(), marked.size());
  FreeSpaceGrid restored(1, kRangeM);
  for (size_t i = 0; i < tiles.size(); ++i) {
    if (i > 0) {
      ASSERT_LT(tiles[i - 1].first, tiles[i].first);
    }
    restored.RestoreTile(tiles[i].first, *tiles[i].second);
  }
  ASSERT_EQ(restored.tile_count(), marked.size());
  for (size_t i = 0; i < marked.size(); ++i) {
    ASSERT_TRUE(restored.IsFree(marked[i])) << i;
    ASSERT_FALSE(restored.IsFree(unmarked[i])) << i;
  }
}

TEST(FreeSpaceGridTest, SkippingQuietRowsChangesNothing) {
  for (const uint32_t min_count : {1u, 3u}) {
    FreeSpaceGrid skipping(min_count, 30.0), reference(min_count, 30.0);
    reference.set_skip_quiet_rows(false);
    std::mt19937 rng(min_count);
    std::uniform_real_distribution<double> pos(-12.0, 12.0), far(-60.0, 60.0), len(0.05, 8.0),
        angle(-3.2, 3.2);
    for (int view = 0; view < 4000; ++view) {
      const Vec2 origin(pos(rng), pos(rng));
      const Vec2 a = view % 7 == 0 ? Vec2(far(rng), far(rng)) : Vec2(pos(rng), pos(rng));
      const double t = angle(rng);
      const Segment2 segment{a, a + len(rng) * Vec2(std::cos(t), std::sin(t))};
      if (view % 5 == 0) {
        const uint64_t cell = FreeSpaceGrid::CellKeyOf(Vec2(pos(rng), pos(rng)));
        const bool on = rng() % 2 == 0;
        skipping.Watch(cell, on);
        reference.Watch(cell, on);
      }
      skipping.AddView(origin, segment);
      reference.AddView(origin, segment);
      ASSERT_EQ(skipping.TakeNewlyFree(), reference.TakeNewlyFree()) << "view " << view;
      ASSERT_EQ(skipping.TakeWatchedPasses(), reference.TakeWatchedPasses()) << "view " << view;
    }
    const auto tiles = skipping.SortedTiles(), reference_tiles = reference.SortedTiles();
    ASSERT_EQ(tiles.size(), reference_tiles.size());
    for (size_t i = 0; i < tiles.size(); ++i) {
      EXPECT_EQ(tiles[i].first, reference_tiles[i].first);
      EXPECT_EQ(*tiles[i].second, *reference_tiles[i].second);
    }
  }
}

TEST(OccludedGapTest, AGapBehindAnOccluderJoins) {
  FusionEngine off(WithEvidence(0.0));
  Feed(&off, Street(/*fence=*/true, /*open_gap=*/false));
  EXPECT_EQ(OnWallLine(off).size(), 2u) << "without evidence the 6 m gap keeps two pieces";

  FusionEngine engine(WithEvidence(10.0));
  Feed(&engine, Street(true, false));
  const auto wall = OnWallLine(engine);
  ASSERT_EQ(wall.size(), 1u);
  EXPECT_NEAR(wall[0].first, 0.0, 0.05);
  EXPECT_NEAR(wall[0].second, 26.0, 0.05);
  EXPECT_EQ(engine.published_count(), 2u);  // the wall and the fence

  FusionEngine short_reach(WithEvidence(5.0));  // less than the gap
  Feed(&short_reach, Street(true, false));
  EXPECT_EQ(OnWallLine(short_reach).size(), 2u);

  // The 6 m gap is more than 0.5 times the 10 m pieces: an unseen stretch that
  // long is not taken for a wall.
  FusionParams strict = WithEvidence(10.0);
  strict.wall_occluded_gap_ratio = 0.5;
  FusionEngine strict_engine(strict);
  Feed(&strict_engine, Street(true, false));
  EXPECT_EQ(OnWallLine(strict_engine).size(), 2u);
  strict.wall_occluded_gap_ratio = 0.7;  // 7 m >= 6 m: joins again
  FusionEngine lenient_engine(strict);
  Feed(&lenient_engine, Street(true, false));
  EXPECT_EQ(OnWallLine(lenient_engine).size(), 1u);

  // Without sensor origins there is no evidence at all, and no occluded join:
  // the map is what it was before evidence existed.
  FusionEngine blind(WithEvidence(10.0));
  for (const Obs& o : Street(true, false)) ASSERT_TRUE(blind.Add(o.id, 1, o.features).ok());
  EXPECT_EQ(OnWallLine(blind).size(), 2u);
}

TEST(OccludedGapTest, AGapSeenThroughDoesNotJoin) {
  FusionEngine engine(WithEvidence(10.0));
  Feed(&engine, Street(/*fence=*/false, /*open_gap=*/true));
  const auto wall = OnWallLine(engine);
  ASSERT_EQ(wall.size(), 2u);
  EXPECT_NEAR(wall[0].second, 10.0, 0.05);
  EXPECT_NEAR(wall[1].first, 16.0, 0.05);
}

TEST(OccludedGapTest, EvidenceArrivingLaterPartsAJoinedWall) {
  FusionEngine engine(WithEvidence(10.0));
  Feed(&engine, Street(/*fence=*/false, /*open_gap=*/false));
  ASSERT_EQ(OnWallLine(engine).size(), 1u) << "nothing seen of the gap yet";
  std::vector<Obs> through;
  for (const Obs& o : Street(false, true)) {
    if (o.features[0].segment.a.y() > 5.0) through.push_back(o);  // the back wall's
  }
  ASSERT_EQ(through.size(), 4u);
  ChangeFeed feed;
  ObservationId id = 100;
  FeatureId fid = 1000;
  for (Obs o : through) {
    for (GroundFeature& f : o.features) f.id = fid++;
    ASSERT_TRUE(engine.AddFrom(id++, 1, o.origin, o.features, &feed).ok());
  }
  EXPECT_EQ(OnWallLine(engine).size(), 2u);
}

TEST(OccludedGapTest, APieceSpanningASeenFreeStretchJoinsNothing) {
  // The two pieces and the back wall, plus a raw segment seen at a grazing
  // angle across the whole facade line (both pieces and the opening).
  std::vector<Obs> observations = Street(false, true);
  FeatureId id = 5000;
  for (ObservationId k = 0; k < 3; ++k) {
    GroundFeature f;
    f.id = id++;
    f.segment = {Vec2(0.0, 0.004), Vec2(26.0, 0.004)};
    observations.push_back({200 + k, Vec2(-30.0, -1.0), {f}});
  }
  FusionEngine off(WithEvidence(0.0));
  Feed(&off, observations);
  EXPECT_EQ(OnWallLine(off).size(), 1u) << "the spanning piece joins both";
  FusionEngine engine(WithEvidence(10.0));
  Feed(&engine, observations);
  EXPECT_EQ(OnWallLine(engine).size(), 3u) << "both pieces and the pierced one, apart";
}

TEST(OccludedGapTest, TheMapDoesNotDependOnArrivalOrder) {
  std::vector<Obs> observations = Street(true, false);
  for (Obs& o : Street(false, true)) {  // a second street, 40 m further on
    for (GroundFeature& f : o.features) {
      f.id += 10000;
      f.segment.a.x() += 40.0;
      f.segment.b.x() += 40.0;
    }
    o.id += 10000;
    o.origin.x() += 40.0;
    observations.push_back(std::move(o));
  }
  FusionEngine reference(WithEvidence(10.0));
  Feed(&reference, observations);
  const std::string expected = Describe(reference.Published());
  ASSERT_EQ(OnWallLine(reference).size(), 3u);  // joined behind the fence, apart where open
  std::mt19937 rng(7);
  for (int trial = 0; trial < 10; ++trial) {
    std::shuffle(observations.begin(), observations.end(), rng);
    FusionEngine engine(WithEvidence(10.0));
    Feed(&engine, observations);
    EXPECT_EQ(Describe(engine.Published()), expected) << "trial " << trial;
  }
}

TEST(OccludedGapTest, SnapshotRoundTripKeepsTheEvidence) {
  std::vector<Obs> observations = Street(false, true);
  std::vector<Obs> later;
  // The back wall's views come after the snapshot: they must part the wall
  // the restored engine joined, as they do in the live one.
  for (auto it = observations.begin(); it != observations.end();) {
    if (it->features[0].segment.a.y() > 5.0 && later.size() < 3) {
      later.push_back(*it);
      it = observations.erase(it);
    } else {
      ++it;
    }
  }
  const FusionParams params = WithEvidence(10.0, FusionMode::kBounded);
  FusionEngine live(params);
  Feed(&live, observations);
  std::string state;
  ASSERT_TRUE(live.SaveState(&state).ok());
  auto restored = FusionEngine::LoadState(params, state);
  ASSERT_TRUE(restored.ok()) << restored.status().ToString();
  EXPECT_EQ(Describe((*restored)->Published()), Describe(live.Published()));
  std::string again;
  ASSERT_TRUE((*restored)->SaveState(&again).ok());
  EXPECT_EQ(again, state);
  const size_t before = OnWallLine(live).size();
  Feed(&live, later);
  Feed(restored->get(), later);
  EXPECT_EQ(Describe((*restored)->Published()), Describe(live.Published()));
  EXPECT_EQ(OnWallLine(live).size(), 2u);
  EXPECT_EQ(before, 1u) << "one view of the opening is below min_count";
  // Other evidence settings: refused (the params key records them).
  FusionParams other = params;
  other.wall_free_min_count = 3;
  EXPECT_FALSE(FusionEngine::LoadState(other, state).ok());
  // A corrupt tile is refused.
  std::string corrupt = state;
  corrupt[corrupt.size() - 20] ^= 0x5a;
  EXPECT_FALSE(FusionEngine::LoadState(params, corrupt).ok());
}

TEST(OccludedGapTest, ParamsAreValidated) {
  FusionParams p;
  p.wall_occluded_gap_m = -1.0;
  EXPECT_FALSE(p.Validate().ok());
  p.wall_occluded_gap_m = 12.0;
  EXPECT_TRUE(p.Validate().ok());
  p.wall_free_min_count = 0;
  EXPECT_FALSE(p.Validate().ok());
  p.wall_free_min_count = 256;
  EXPECT_FALSE(p.Validate().ok());
  p.wall_free_min_count = 5;
  p.wall_occluded_gap_ratio = 0.0;
  EXPECT_NE(p.Validate().ToString().find("wall_occluded_gap_ratio"), std::string::npos);
  p.wall_occluded_gap_ratio = NAN;
  EXPECT_FALSE(p.Validate().ok());
  FusionEngine engine(WithEvidence(10.0));
  GroundFeature f;
  f.id = 1;
  f.segment = {Vec2(0, 0), Vec2(1, 0)};
  EXPECT_FALSE(engine.AddFrom(1, 1, Vec2(NAN, 0.0), {f}).ok());
  EXPECT_EQ(engine.feature_count(), 0u);
}

}  // namespace
}  // namespace mapd::fusion
