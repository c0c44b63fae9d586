// FusionMode::kBounded against kExact: a revisited wall keeps a bounded number
// of nodes and publishes what the exact engine publishes.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <random>
#include <string>

#include "fusion/engine.h"
#include "fusion/state_codec.h"

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

// With refit_tolerance_m 0 the exact map; with the default, the same walls
// and counts, their geometry within the tolerance (settled walls).
class RevisitedWallsTest : public ::testing::TestWithParam<double> {};

TEST_P(RevisitedWallsTest, KeepFewNodesAndTheExactMap) {
  const double tolerance_m = GetParam();
  FusionEngine exact(Mode(FusionMode::kExact));
  FusionParams bounded_params = Mode(FusionMode::kBounded);
  bounded_params.refit_tolerance_m = tolerance_m;
  FusionEngine bounded(bounded_params);
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
    EXPECT_LE((b[i].segment.a - e[i].segment.a).norm(), 1e-6 + tolerance_m);
    EXPECT_LE((b[i].segment.b - e[i].segment.b).norm(), 1e-6 + tolerance_m);
    // Support past the exact cap is a count that may only overcount
    // (support_counter.h); here no two pieces ever merged, so it is exact.
    EXPECT_EQ(b[i].support, e[i].support);
  }
}

INSTANTIATE_TEST_SUITE_P(BoundedEngineTest, RevisitedWallsTest,
                         ::testing::Values(0.0, FusionParams().refit_tolerance_m));

TEST(BoundedEngineTest, YoungClustersFoldNothing) {
  // Below the established support every feature stays a node, as in exact mode.
  FusionEngine bounded(Mode(FusionMode::kBounded));
  std::mt19937_64 rng(3);
  for (ObservationId o = 1; o <= 20; ++o) ASSERT_TRUE(bounded.Add(o, 0, View(o, &rng)).ok());
  EXPECT_EQ(bounded.node_count(), 60u);
}

// The revisited site plus a curved wall (the chain guard cuts it), so that
// folding, cuts and corners all carry state across a snapshot.
std::vector<GroundFeature> SiteView(ObservationId observation, std::mt19937_64* rng) {
  std::vector<GroundFeature> out = View(observation, rng);
  // A wall curving through 0.6 rad on a 20 m radius, seen as 1 m chords that
  // start at a random phase: chords of different views overlap and chain
  // along the arc, which the guard then cuts into straight pieces.
  std::uniform_real_distribution<double> phase(0.0, 0.05);
  const double start = phase(*rng);
  for (int k = 0; k < 11; ++k) {
    const double t0 = start + 0.05 * k, t1 = t0 + 0.05;
    GroundFeature f;
    f.id = (observation << 4) | static_cast<FeatureId>(4 + k);
    f.segment = {Vec2(30 + 20 * std::sin(t0), 20 * std::cos(t0)),
                 Vec2(30 + 20 * std::sin(t1), 20 * std::cos(t1))};
    f.z_max_m = 2.0;
    out.push_back(f);
  }
  return out;
}

std::string State(const FusionEngine& engine) {
  std::string bytes;
  EXPECT_TRUE(engine.SaveState(&bytes).ok());
  return bytes;
}

void ExpectSameMap(const FusionEngine& a, const FusionEngine& b) {
  const std::vector<FusedFeature> fa = a.Published(), fb = b.Published();
  ASSERT_EQ(fa.size(), fb.size());
  for (size_t i = 0; i < fa.size(); ++i) {
    EXPECT_EQ(fa[i].id, fb[i].id);
    EXPECT_EQ(fa[i].segment.a, fb[i].segment.a);  // bit for bit
    EXPECT_EQ(fa[i].segment.b, fb[i].segment.b);
    EXPECT_EQ(fa[i].fitted.a, fb[i].fitted.a);
    EXPECT_EQ(fa[i].support, fb[i].support);
    EXPECT_EQ(fa[i].member_count, fb[i].member_count);
    EXPECT_EQ(fa[i].robots, fb[i].robots);
  }
  EXPECT_EQ(a.node_count(), b.node_count());
  EXPECT_EQ(a.cluster_count(), b.cluster_count());
  EXPECT_EQ(a.feature_count(), b.feature_count());
}

class SnapshotTest : public ::testing::TestWithParam<uint32_t> {};

TEST_P(SnapshotTest, SnapshotPlusReplayEqualsFullReplay) {
  const uint32_t seed = GetParam();
  std::mt19937_64 rng(seed);
  std::vector<std::vector<GroundFeature>> views;
  constexpr ObservationId kObservations = 80;  // folding starts at 32 (established)
  for (ObservationId o = 1; o <= kObservations; ++o) views.push_back(SiteView(o, &rng));
  const FusionParams params = Mode(FusionMode::kBounded);
  const ObservationId cut = 1 + rng() % (kObservations - 1);

  FusionEngine full(params);
  std::unique_ptr<FusionEngine> restored;
  for (ObservationId o = 1; o <= kObservations; ++o) {
    ASSERT_TRUE(full.Add(o, o % 3, views[o - 1]).ok());
    if (o == cut) {
      StatusOr<std::unique_ptr<FusionEngine>> loaded = FusionEngine::LoadState(params, State(full));
      ASSERT_TRUE(loaded.ok()) << loaded.status().ToString();
      restored = std::move(loaded).value();
      ExpectSameMap(full, *restored);
    } else if (o > cut) {
      ASSERT_TRUE(restored->Add(o, o % 3, views[o - 1]).ok());
    }
  }
  ASSERT_GT(full.feature_count(), full.node_count()) << "nothing was folded: the test tests little";
  ASSERT_GE(full.Published().size(), 6u) << "the guard did not cut the arc: the test tests little";
  ExpectSameMap(full, *restored);
  EXPECT_EQ(State(full), State(*restored));  // the whole state, not just the map
}

INSTANTIATE_TEST_SUITE_P(Seeds, SnapshotTest, ::testing::Range(1u, 6u));

// ---- Settled walls (FusionParams::refit_tolerance_m) -----------------------

// The revisited site with free-space evidence: every view from a sensor in
// front of the walls, as mapd feeds it.
Status AddSite(FusionEngine* engine, ObservationId o, const std::vector<GroundFeature>& view,
               ChangeFeed* changes = nullptr) {
  return engine->AddFrom(o, o % 3, Vec2(10.0, -4.0), view, changes);
}

// Folds into established walls leave their geometry within the tolerance of
// the exact refit; their counts are exact (as with tolerance 0); and a
// snapshot taken among settled walls restores bit for bit.
TEST(SettledWallsTest, KeepGeometryWithinTheToleranceAndCountsExact) {
  FusionParams every_refit = Mode(FusionMode::kBounded);
  every_refit.refit_tolerance_m = 0.0;
  const FusionParams settling = Mode(FusionMode::kBounded);
  ASSERT_GT(settling.refit_tolerance_m, 0.0) << "the default settles";
  FusionEngine reference(every_refit), engine(settling);
  std::unique_ptr<FusionEngine> restored;
  std::mt19937_64 rng(11);
  constexpr ObservationId kObservations = 400, kCut = 250;
  size_t geometry_differs = 0;
  for (ObservationId o = 1; o <= kObservations; ++o) {
    const std::vector<GroundFeature> view = SiteView(o, &rng);
    ASSERT_TRUE(AddSite(&reference, o, view).ok());
    ASSERT_TRUE(AddSite(&engine, o, view).ok());
    if (restored) {
      ASSERT_TRUE(AddSite(restored.get(), o, view).ok());
    }
    if (o == kCut) {
      StatusOr<std::unique_ptr<FusionEngine>> loaded =
          FusionEngine::LoadState(settling, State(engine));
      ASSERT_TRUE(loaded.ok()) << loaded.status().ToString();
      restored = std::move(loaded).value();
    }
    if (o % 50 != 0) continue;
    const std::vector<FusedFeature> r = reference.Published(), e = engine.Published();
    ASSERT_EQ(r.size(), e.size()) << "at observation " << o;
    for (size_t i = 0; i < r.size(); ++i) {
      ASSERT_EQ(e[i].id, r[i].id);
      EXPECT_EQ(e[i].member_count, r[i].member_count) << e[i].id;
      EXPECT_EQ(e[i].support, r[i].support) << e[i].id;
      EXPECT_EQ(e[i].robots, r[i].robots) << e[i].id;
      EXPECT_EQ(e[i].z_max_m, r[i].z_max_m) << e[i].id;
      const double fitted_m =
          std::max((e[i].fitted.a - r[i].fitted.a).norm(), (e[i].fitted.b - r[i].fitted.b).norm());
      const double segment_m = std::max((e[i].segment.a - r[i].segment.a).norm(),
                                        (e[i].segment.b - r[i].segment.b).norm());
      // A one-piece wall's fit is within the tolerance; a wall of pieces and
      // a corner between two walls may move by a little more.
      EXPECT_LE(fitted_m, 2.0 * settling.refit_tolerance_m) << e[i].id;
      EXPECT_LE(segment_m, 2.0 * settling.refit_tolerance_m) << e[i].id;
      geometry_differs += fitted_m > 0.0;
    }
  }
  EXPECT_GT(geometry_differs, 0u) << "nothing settled: the test tests little";
  ExpectSameMap(engine, *restored);
  EXPECT_EQ(State(engine), State(*restored));
}

// A fold that settles still reports its wall as updated, with the new count,
// and leaves its fitted segment where it was.
TEST(SettledWallsTest, AFoldThatSettlesReportsTheNewCounts) {
  FusionEngine engine(Mode(FusionMode::kBounded));
  std::mt19937_64 rng(5);
  ObservationId o = 1;
  for (; o <= 600; ++o) ASSERT_TRUE(AddSite(&engine, o, View(o, &rng)).ok());
  const std::vector<FusedFeature> before = engine.Published();
  ASSERT_EQ(before.size(), 3u);
  // The walls' own average view: folds into every representative it meets
  // and moves no fit by a millimetre.
  std::vector<GroundFeature> view = View(o, &rng);
  const Segment2 walls[] = {{{0, 0}, {8, 0}}, {{8, 0.2}, {8, 6}}, {{12, 3}, {20, 3}}};
  for (int k = 0; k < 3; ++k) view[k].segment = walls[k];
  const size_t nodes = engine.node_count();
  ChangeFeed changes;
  ASSERT_TRUE(AddSite(&engine, o, view, &changes).ok());
  ASSERT_EQ(engine.node_count(), nodes) << "the view did not fold";
  const std::vector<FusedFeature> after = engine.Published();
  ASSERT_EQ(after.size(), 3u);
  std::vector<ClusterId> ids;
  for (size_t i = 0; i < 3; ++i) {
    ids.push_back(after[i].id);
    EXPECT_EQ(after[i].member_count, before[i].member_count + 1) << after[i].id;
    EXPECT_EQ(after[i].fitted.a, before[i].fitted.a) << "settled walls keep their geometry";
    EXPECT_EQ(after[i].fitted.b, before[i].fitted.b);
    EXPECT_EQ(after[i].segment.a, before[i].segment.a);
  }
  EXPECT_EQ(changes.updated, ids);
  EXPECT_TRUE(changes.added.empty());
  EXPECT_TRUE(changes.removed.empty());
}

TEST(SnapshotStateTest, RefusesCorruptOrForeignState) {
  std::mt19937_64 rng(1);
  FusionEngine engine(Mode(FusionMode::kBounded));
  for (ObservationId o = 1; o <= 50; ++o) ASSERT_TRUE(engine.Add(o, 0, SiteView(o, &rng)).ok());
  const std::string good = State(engine);
  const FusionParams params = Mode(FusionMode::kBounded);
  ASSERT_TRUE(FusionEngine::LoadState(params, good).ok());

  EXPECT_EQ(FusionEngine::LoadState(params, "").status().code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(FusionEngine::LoadState(params, good.substr(0, good.size() / 2)).status().code(),
            StatusCode::kInvalidArgument);
  std::string flipped = good;
  flipped[flipped.size() / 2] ^= 0x40;
  const Status corrupt = FusionEngine::LoadState(params, flipped).status();
  EXPECT_EQ(corrupt.code(), StatusCode::kInvalidArgument);
  EXPECT_NE(corrupt.message().find("checksum"), std::string::npos) << corrupt.message();

  FusionParams other = params;
  other.eta_m = 0.4;
  const Status foreign = FusionEngine::LoadState(other, good).status();
  EXPECT_EQ(foreign.code(), StatusCode::kFailedPrecondition);
  EXPECT_NE(foreign.message().find("fusion snapshot was taken with other parameters"),
            std::string::npos);

  std::string unused;
  FusionEngine exact(Mode(FusionMode::kExact));
  EXPECT_EQ(exact.SaveState(&unused).code(), StatusCode::kUnimplemented);
}

// Version 3 changed only the checksum (FNV-1a -> WordChecksum): a database
// written by an older mapd still starts from its snapshot, and any bit that
// changes is caught by either.
TEST(SnapshotStateTest, ReadsVersion2AndEveryFlippedBitIsCaught) {
  std::mt19937_64 rng(2);
  FusionEngine engine(Mode(FusionMode::kBounded));
  for (ObservationId o = 1; o <= 50; ++o) ASSERT_TRUE(engine.Add(o, 0, SiteView(o, &rng)).ok());
  const FusionParams params = Mode(FusionMode::kBounded);
  const std::string good = State(engine);
  constexpr size_t kVersionAt = 8;  // after the magic
  ASSERT_EQ(static_cast<uint8_t>(good[kVersionAt]), 3u);

  const auto close = [](std::string body, uint8_t version, bool fnv) {
    body[kVersionAt] = static_cast<char>(version);
    const uint64_t sum = fnv ? Fnv1a(body) : WordChecksum(body);
    body.append(reinterpret_cast<const char*>(&sum), 8);
    return body;
  };
  const std::string body = good.substr(0, good.size() - 8);
  StatusOr<std::unique_ptr<FusionEngine>> old =
      FusionEngine::LoadState(params, close(body, 2, true));
  ASSERT_TRUE(old.ok()) << old.status().ToString();
  EXPECT_EQ(State(**old), good);  // and saved again as version 3
  // Each format with the other's checksum, and a format from the future.
  EXPECT_NE(
      FusionEngine::LoadState(params, close(body, 2, false)).status().message().find("checksum"),
      std::string::npos);
  EXPECT_NE(
      FusionEngine::LoadState(params, close(body, 3, true)).status().message().find("checksum"),
      std::string::npos);
  EXPECT_NE(FusionEngine::LoadState(params, close(body, 4, false))
                .status()
                .message()
                .find("unknown format version 4"),
            std::string::npos);

  // Every single bit of the body (past the version), one at a time, in a
  // stretch of 1 KiB that covers lanes, words and the tail.
  const size_t from = body.size() > 1024 ? body.size() - 1024 : kVersionAt + 4;
  for (size_t byte = from; byte < body.size(); ++byte) {
    for (int bit = 0; bit < 8; ++bit) {
      std::string flipped = good;
      flipped[byte] ^= static_cast<char>(1 << bit);
      ASSERT_NE(WordChecksum(std::string_view(flipped).substr(0, body.size())), WordChecksum(body))
          << "byte " << byte << " bit " << bit;
    }
  }
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

// Upgrades: a snapshot taken without settled walls (every release before
// them) loads into an engine with them, which continues from it; a snapshot
// with settled walls does not load without them (its pieces' copies may be
// older than their clusters): that engine replays instead.
TEST(SettledWallsTest, SnapshotsWithoutThemLoadButNotTheReverse) {
  FusionParams every_refit = Mode(FusionMode::kBounded);
  every_refit.refit_tolerance_m = 0.0;
  const FusionParams settling = Mode(FusionMode::kBounded);
  FusionEngine old_release(every_refit), settled(settling);
  std::mt19937_64 rng(9);
  for (ObservationId o = 1; o <= 300; ++o) {
    const std::vector<GroundFeature> view = View(o, &rng);
    ASSERT_TRUE(AddSite(&old_release, o, view).ok());
    ASSERT_TRUE(AddSite(&settled, o, view).ok());
  }
  StatusOr<std::unique_ptr<FusionEngine>> upgraded =
      FusionEngine::LoadState(settling, State(old_release));
  ASSERT_TRUE(upgraded.ok()) << upgraded.status().ToString();
  ExpectSameMap(old_release, **upgraded);
  for (ObservationId o = 301; o <= 400; ++o) {
    const std::vector<GroundFeature> view = View(o, &rng);
    ASSERT_TRUE(AddSite(upgraded->get(), o, view).ok());
    ASSERT_TRUE(AddSite(&old_release, o, view).ok());
  }
  const std::vector<FusedFeature> a = (*upgraded)->Published(), b = old_release.Published();
  ASSERT_EQ(a.size(), b.size());
  for (size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a[i].member_count, b[i].member_count);
    EXPECT_LE((a[i].fitted.a - b[i].fitted.a).norm(), 2.0 * settling.refit_tolerance_m);
  }
  const StatusOr<std::unique_ptr<FusionEngine>> downgraded =
      FusionEngine::LoadState(every_refit, State(settled));
  ASSERT_FALSE(downgraded.ok());
  EXPECT_EQ(downgraded.status().code(), StatusCode::kFailedPrecondition);
  EXPECT_NE(downgraded.status().message().find("other parameters"), std::string::npos)
      << downgraded.status().ToString();
}

}  // namespace
}  // namespace mapd::fusion
