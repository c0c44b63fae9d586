// Piercing (fusion/piercing.h): the check against its own samples, the
// clearance it reports, and the consolidator keeping a refitted piece's flag
// without a fresh check only while the clearance allows.
#include "fusion/piercing.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>

#include "fusion/cluster_stats.h"
#include "fusion/params.h"
#include "fusion/wall_consolidation.h"

namespace mapd::fusion {
namespace {

using geometry::Segment2;
using geometry::Vec2;

// Whether any piercing sample of s is free: the definition, sample by sample.
bool AnySampleFree(const Segment2& s, const FreeSpaceGrid& grid) {
  const double length = s.length();
  if (!(length > 2.0 * kPierceTrimM)) return false;
  const Vec2 u = s.direction() / length;
  const double t0 = kPierceTrimM, t1 = length - kPierceTrimM;
  const int steps = SampleSteps(t0, t1);
  for (int i = 0; i <= steps; ++i) {
    if (grid.IsFree(SampleAt(s.a, u, t0, t1, i, steps))) return true;
  }
  return false;
}

// Free space with ragged edges: a fan of views of a wall, some far off to
// the side (narrow triangles).
FreeSpaceGrid Fan() {
  FreeSpaceGrid grid(1, 80.0);
  for (int k = -4; k <= 4; ++k) {
    grid.AddView(Vec2(3.0 * k, -12.0), {Vec2(-6.0 + k, 0.0), Vec2(-2.0 + k, 0.3)});
  }
  return grid;
}

TEST(PiercingTest, ItsClearanceKeepsEveryMoveWithinItUnpierced) {
  const FreeSpaceGrid grid = Fan();
  std::mt19937 rng(17);
  std::uniform_real_distribution<double> x(-16.0, 10.0), y(-13.0, 2.0), length(1.2, 5.0),
      angle(0.0, 6.3), jitter(-0.01, 0.01);
  int unpierced = 0, near_free = 0, moves_checked = 0;
  for (int trial = 0; trial < 20000; ++trial) {
    const Vec2 centre(x(rng), y(rng));
    const double a = angle(rng);
    const Vec2 half = 0.5 * length(rng) * Vec2(std::cos(a), std::sin(a));
    const Segment2 s{centre - half, centre + half};
    const PierceCheck check = CheckPiercing(s, grid);
    ASSERT_EQ(check.pierced, AnySampleFree(s, grid)) << "trial " << trial;
    if (check.pierced) continue;
    ++unpierced;
    ASSERT_GE(check.clearance_m, 0.0);
    ASSERT_LE(check.clearance_m, kPierceClearanceCapM);
    if (check.clearance_m < kPierceClearanceCapM) ++near_free;
    for (int move = 0; move < 20; ++move) {
      const double scale = 0.05 * move;  // from tiny moves to ones beyond the cap
      const Segment2 t{s.a + scale * Vec2(jitter(rng), jitter(rng)),
                       s.b + scale * Vec2(jitter(rng), jitter(rng))};
      if (SampleShiftBound(s, t) >= check.clearance_m) continue;
      ++moves_checked;
      ASSERT_FALSE(AnySampleFree(t, grid)) << "trial " << trial << " move " << move;
    }
  }
  // The scene tests something: unpierced segments near free cells, and moves.
  EXPECT_GT(unpierced, 2000);
  EXPECT_GT(near_free, 100);
  EXPECT_GT(moves_checked, 10000);
  std::printf("%d unpierced segments, %d near free cells, %d moves within the clearance\n",
              unpierced, near_free, moves_checked);
}

// One free cell, [0, 0.25) x [0, 0.25): the clearance of a segment whose
// first sample lies 1 cm off one of its corners (diagonally), 1.5 cm off
// one of its sides, or more than the cap away.
TEST(PiercingTest, TheClearanceIsTheNearestFreeNeighbour) {
  FreeSpaceGrid grid(1, 80.0);
  grid.AddLine({Vec2(0.1, 0.1), Vec2(0.15, 0.15)});
  ASSERT_TRUE(grid.IsFree(Vec2(0.125, 0.125)));
  ASSERT_FALSE(grid.IsFree(Vec2(0.375, 0.125)));
  // Horizontal, 2 m long: its samples run from a.x + 0.5 every 0.125 m.
  const auto from_first_sample = [](const Vec2& first) {
    return Segment2{first - Vec2(kPierceTrimM, 0.0), first + Vec2(1.5, 0.0)};
  };
  const PierceCheck diagonal = CheckPiercing(from_first_sample(Vec2(0.26, -0.01)), grid);
  EXPECT_FALSE(diagonal.pierced);
  EXPECT_NEAR(diagonal.clearance_m, 0.01, 1e-9);
  const PierceCheck side = CheckPiercing(from_first_sample(Vec2(0.265, 0.1)), grid);
  EXPECT_FALSE(side.pierced);
  EXPECT_NEAR(side.clearance_m, 0.015, 1e-9);
  const PierceCheck far = CheckPiercing(from_first_sample(Vec2(0.3, 0.1)), grid);
  EXPECT_EQ(far.clearance_m, kPierceClearanceCapM);
  const PierceCheck on = CheckPiercing(from_first_sample(Vec2(0.2, 0.1)), grid);
  EXPECT_TRUE(on.pierced);
  EXPECT_EQ(on.clearance_m, 0.0);
}

TEST(PiercingTest, SampleShiftBoundCoversEverySample) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> coord(-30.0, 30.0), jitter(-0.05, 0.05);
  for (int trial = 0; trial < 2000; ++trial) {
    const Segment2 s{Vec2(coord(rng), coord(rng)), Vec2(coord(rng), coord(rng))};
    const Segment2 t{s.a + Vec2(jitter(rng), jitter(rng)), s.b + Vec2(jitter(rng), jitter(rng))};
    const double bound = SampleShiftBound(s, t);
    const double ls = s.length(), lt = t.length();
    const int steps = SampleSteps(kPierceTrimM, ls - kPierceTrimM);
    if (steps != SampleSteps(kPierceTrimM, lt - kPierceTrimM)) {
      EXPECT_TRUE(std::isinf(bound));
      continue;
    }
    for (int i = 0; i <= steps; ++i) {
      const Vec2 p = SampleAt(s.a, s.direction() / ls, kPierceTrimM, ls - kPierceTrimM, i, steps);
      const Vec2 q = SampleAt(t.a, t.direction() / lt, kPierceTrimM, lt - kPierceTrimM, i, steps);
      ASSERT_LE((q - p).norm(), bound) << "trial " << trial << " sample " << i;
    }
  }
  EXPECT_TRUE(std::isinf(SampleShiftBound({Vec2(0, 0), Vec2(0.9, 0)}, {Vec2(0, 0), Vec2(0.9, 0)})))
      << "too short to sample";
}

ClusterStats Piece(FeatureId id, const Segment2& s, uint32_t members) {
  GroundFeature f;
  f.id = id;
  f.segment = s;
  ClusterStats stats = ClusterStats::OfFeature(f, 1, 0);
  for (uint32_t m = 1; m < members; ++m) stats.AddFeature(f, 1 + m, 0, 64);
  return stats;
}

// A piece refitted by two millimetres, from beside a free cell onto it, is
// pierced: its clearance there was below the move, so it was checked afresh.
TEST(PiercingTest, ARefitOntoAFreeCellPiercesThePiece) {
  FusionParams params;
  WallConsolidator consolidator(params, 64);
  for (int k = 0; k < 3; ++k) consolidator.AddView(Vec2(0.0, -10.0), {Vec2(-5, 0), Vec2(5, 0)});
  const FreeSpaceGrid& grid = *consolidator.free_space();
  // A vertical line whose samples (y from -5.5 to -4.5) are all not free in
  // one column of cells and not all not free in the column to its left.
  const auto column_free = [&](double x) {
    return AnySampleFree({Vec2(x, -6.0), Vec2(x, -4.0)}, grid);
  };
  double edge = -1.0;
  for (double x = 0.0; x < 6.0; x += FreeSpaceGrid::kCellM) {
    if (column_free(x + 0.125) && !column_free(x + 0.375)) {
      edge = x + 0.25;
      break;
    }
  }
  ASSERT_GT(edge, 0.0) << "no edge of the free space found";
  const Segment2 beside{Vec2(edge + 0.001, -6.0), Vec2(edge + 0.001, -4.0)};
  const Segment2 onto{Vec2(edge - 0.001, -6.0), Vec2(edge - 0.001, -4.0)};
  ASSERT_FALSE(Pierced(beside, grid));
  ASSERT_TRUE(Pierced(onto, grid));
  const size_t mismatches = WallConsolidator::piercing_mismatches();
  WallConsolidator::SetVerifyNeighbourCache(true);
  std::vector<ClusterId> removed;
  std::vector<WallConsolidator::Wall> walls;
  const ClusterStats first = Piece(100, beside, 3);
  ASSERT_TRUE(consolidator.Upsert(first, {first.Refit().line, beside}));
  consolidator.Resolve(&removed, &walls);
  const ClusterStats second = Piece(100, onto, 4);
  ASSERT_TRUE(consolidator.Upsert(second, {second.Refit().line, onto}));
  consolidator.Resolve(&removed, &walls);
  EXPECT_EQ(WallConsolidator::piercing_mismatches(), mismatches);
}

}  // namespace
}  // namespace mapd::fusion
