// FusionParams::max_wall_pieces: wall consolidation joins the pieces of a
// connected set of at most that many; the pieces of a larger one are each a
// wall of their own, and join again once the set is small again. The result
// stays a function of the pieces: a snapshot (which resolves every piece from
// scratch) loads, and other arrival orders publish the same walls.
#include <gtest/gtest.h>

#include <algorithm>
#include <memory>
#include <random>
#include <vector>

#include "fusion/engine.h"

// Named, so that a unity build with the other fusion tests sees no clash.
namespace mapd::fusion::wall_pieces_cap_test {
namespace {

using geometry::Vec2;

constexpr int kPieces = 20;

FusionParams Params(uint32_t max_wall_pieces) {
  FusionParams p;
  p.mode = FusionMode::kBounded;
  p.max_wall_pieces = max_wall_pieces;
  return p;
}

// One observation of a stretch [x0, x1] of the wall y = 0 (lateral noise of a
// millimetre, so that no two are identical).
struct View {
  ObservationId observation;
  double x0, x1;
};

// Piece k: [10k - 0.2, 10k + 10], seen 3 times. Criterion 3 never links two
// pieces (their centres are 10 m apart); consolidation joins them (they overlap).
std::vector<View> PieceViews() {
  std::vector<View> views;
  ObservationId o = 1;
  for (int k = 0; k < kPieces; ++k) {
    for (int i = 0; i < 3; ++i) views.push_back({o++, 10.0 * k - 0.2, 10.0 * k + 10.0});
  }
  return views;
}

// A stretch [10k + 5, 10k + 15] links pieces k and k + 1 into one cluster
// (each centre lies on the other): one piece fewer.
std::vector<View> BridgeViews(const std::vector<int>& ks, ObservationId first) {
  std::vector<View> views;
  for (int k : ks) views.push_back({first++, 10.0 * k + 5.0, 10.0 * k + 15.0});
  return views;
}

void Feed(FusionEngine* engine, const std::vector<View>& views) {
  for (const View& v : views) {
    GroundFeature f;
    f.id = v.observation << 4;
    const double y = 0.001 * static_cast<double>(v.observation % 7);
    f.segment = {Vec2(v.x0, y), Vec2(v.x1, -y)};
    f.z_max_m = 2.0;
    ASSERT_TRUE(engine->Add(v.observation, 0, {f}).ok());
  }
}

// The engine's state loads: the walls resolved from scratch are the ones it
// maintained incrementally (LoadState refuses the state otherwise).
void ExpectSnapshotLoads(const FusionEngine& engine, const FusionParams& params) {
  std::string state;
  ASSERT_TRUE(engine.SaveState(&state).ok());
  StatusOr<std::unique_ptr<FusionEngine>> loaded = FusionEngine::LoadState(params, state);
  ASSERT_TRUE(loaded.ok()) << loaded.status().ToString();
  EXPECT_EQ((*loaded)->published_count(), engine.published_count());
}

std::vector<ClusterId> Ids(const FusionEngine& engine) {
  std::vector<ClusterId> ids;
  for (const FusedFeature& f : engine.Published()) ids.push_back(f.id);
  return ids;
}

TEST(WallPiecesCapTest, ALineOfMorePiecesThanTheCapIsNotConsolidated) {
  FusionEngine capped(Params(16));
  Feed(&capped, PieceViews());
  EXPECT_EQ(capped.published_count(), static_cast<size_t>(kPieces));
  ExpectSnapshotLoads(capped, Params(16));

  FusionEngine roomy(Params(32));
  Feed(&roomy, PieceViews());
  ASSERT_EQ(roomy.published_count(), 1u) << "the test needs a line consolidation joins";
  const FusedFeature wall = roomy.Published()[0];
  EXPECT_NEAR(std::min(wall.segment.a.x(), wall.segment.b.x()), -0.2, 0.01);
  EXPECT_NEAR(std::max(wall.segment.a.x(), wall.segment.b.x()), 10.0 * kPieces, 0.01);
}

TEST(WallPiecesCapTest, PiecesJoinAgainOnceTheirSetIsWithinTheCap) {
  const FusionParams params = Params(16);
  FusionEngine engine(params);
  std::vector<View> views = PieceViews();
  Feed(&engine, views);
  ASSERT_EQ(engine.published_count(), static_cast<size_t>(kPieces));
  // Four bridges: 16 pieces, one wall again. After each, the state loads.
  ObservationId next = views.back().observation + 1;
  for (int k : {1, 5, 9, 13}) {
    const std::vector<View> bridge = BridgeViews({k}, next++);
    Feed(&engine, bridge);
    views.insert(views.end(), bridge.begin(), bridge.end());
    ExpectSnapshotLoads(engine, params);
  }
  EXPECT_EQ(engine.published_count(), 1u);

  // The same views in another order give the same walls.
  std::vector<View> reversed(views.rbegin(), views.rend());
  FusionEngine other(params);
  Feed(&other, reversed);
  EXPECT_EQ(Ids(other), Ids(engine));
}

TEST(WallPiecesCapTest, APieceJoiningALargeSetEndsItsWalls) {
  // Two lines of 10 pieces, each one wall, then the piece between them: one
  // set of 20 pieces, over the cap, so 20 walls.
  const FusionParams params = Params(16);
  std::vector<View> views = PieceViews();
  const auto middle = std::stable_partition(views.begin(), views.end(), [](const View& v) {
    return !(v.x0 > 99.0 && v.x0 < 100.0);  // piece 10 last
  });
  std::vector<View> last_piece(middle, views.end());
  views.erase(middle, views.end());
  FusionEngine engine(params);
  Feed(&engine, views);
  EXPECT_EQ(engine.published_count(), 2u);
  Feed(&engine, last_piece);
  EXPECT_EQ(engine.published_count(), static_cast<size_t>(kPieces));
  ExpectSnapshotLoads(engine, params);
}

TEST(WallPiecesCapTest, ALargeSetThatFallsApartJoinsItsHalves) {
  // 20 pieces, over the cap; then a robot at (105, -10) sees a wall at
  // y = 10 through piece 10, which is then pierced and joins nothing: two
  // sets of 10, each one wall again, and piece 10 alone.
  const FusionParams params = Params(16);
  FusionEngine engine(params);
  Feed(&engine, PieceViews());
  ASSERT_EQ(engine.published_count(), static_cast<size_t>(kPieces));
  GroundFeature beyond;
  beyond.id = 1000 << 4;
  beyond.segment = {Vec2(103.0, 10.0), Vec2(107.0, 10.0)};
  beyond.z_max_m = 2.0;
  ASSERT_TRUE(engine.AddFrom(1000, 1, Vec2(105.0, -10.0), {beyond}).ok());
  EXPECT_EQ(engine.published_count(), 3u);
  ExpectSnapshotLoads(engine, params);
}

// Random stretches of three long walls, fed one by one: sets of pieces grow
// past the cap, fall back within it as clusters merge, several at once. After
// every observation the walls maintained are those resolved from scratch.
TEST(WallPiecesCapTest, RandomStretchesKeepTheWallsAFunctionOfThePieces) {
  const FusionParams params = Params(16);
  for (uint32_t seed = 1; seed <= 3; ++seed) {
    // Pieces as in PieceViews, 30 a wall, seen in random order; one view in
    // five a bridge (which merges two pieces).
    std::mt19937 rng(seed);
    std::uniform_int_distribution<int> piece(0, 29), kind(0, 4);
    std::uniform_real_distribution<double> jitter(-0.05, 0.05);
    std::vector<View> views;
    for (ObservationId o = 1; o <= 1200; ++o) {
      const double x = 10.0 * piece(rng) + jitter(rng);
      views.push_back(kind(rng) == 0 ? View{o, x + 5.0, x + 15.0} : View{o, x - 0.2, x + 10.0});
    }
    // Three views an observation, of one wall: several pieces of one set
    // change at once.
    FusionEngine engine(params);
    size_t most = 0;
    for (size_t i = 0; i + 3 <= views.size(); i += 3) {
      std::vector<GroundFeature> features;
      for (size_t w = 0; w < 3; ++w) {
        const View& v = views[i + w];
        GroundFeature f;
        f.id = (static_cast<FeatureId>(i) << 4) | w;
        const double y = 5.0 * static_cast<double>(i / 3 % 3) + 0.001 * static_cast<double>(w);
        f.segment = {Vec2(v.x0, y), Vec2(v.x1, y)};
        f.z_max_m = 2.0;
        features.push_back(f);
      }
      ASSERT_TRUE(engine.Add(static_cast<ObservationId>(i + 1), 0, features).ok());
      ASSERT_NO_FATAL_FAILURE(ExpectSnapshotLoads(engine, params)) << "seed " << seed;
      most = std::max(most, engine.published_count());
    }
    EXPECT_GT(most, 16u) << "no set of pieces went past the cap: the test tests little";
    EXPECT_LT(engine.published_count(), most) << "no set came back within the cap";
  }
}

}  // namespace
}  // namespace mapd::fusion::wall_pieces_cap_test
