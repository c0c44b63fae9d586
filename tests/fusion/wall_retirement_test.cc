// Retirement (wall_retirement.h): a published wall that observations see
// through after its last support leaves the published map; a wall merely
// hidden stays; a wall seen again comes back; snapshots carry the evidence.
//
// The scene: a robot at (3, 0) looks north. The wall W runs along y = 5 from
// x = 0 to 6; behind it, B along y = 10 from x = -3 to 9, whose visibility
// triangle covers the whole of W's line; an occluder O along y = 2 hides W.
#include "fusion/wall_retirement.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <memory>
#include <string>
#include <vector>

#include "fusion/engine.h"

// Named, so that a unity build with the other fusion tests sees no clash.
namespace mapd::fusion::wall_retirement_test {
namespace {

using geometry::Segment2;
using geometry::Vec2;

const Vec2 kSensor(3.0, 0.0);
const Segment2 kWall{Vec2(0.0, 5.0), Vec2(6.0, 5.0)};
const Segment2 kBehind{Vec2(-3.0, 10.0), Vec2(9.0, 10.0)};
const Segment2 kOccluder{Vec2(-3.0, 2.0), Vec2(9.0, 2.0)};

class Robot {
 public:
  explicit Robot(FusionEngine* engine) : engine_(engine) {}

  // One observation from kSensor of `segments` (a millimetre of noise per
  // observation, so that no two are identical); returns what changed.
  ChangeFeed See(const std::vector<Segment2>& segments) {
    ++observation_;
    std::vector<GroundFeature> features;
    const double dy = 0.001 * static_cast<double>(observation_ % 5);
    for (const Segment2& s : segments) {
      GroundFeature f;
      f.id = ++feature_;
      f.segment = {s.a + Vec2(0.0, dy), s.b + Vec2(0.0, dy)};
      f.z_max_m = 2.0;
      features.push_back(f);
    }
    ChangeFeed feed;
    EXPECT_TRUE(engine_->AddFrom(observation_, 1, kSensor, features, &feed).ok());
    return feed;
  }
  void See(const std::vector<Segment2>& segments, int times) {
    for (int i = 0; i < times; ++i) See(segments);
  }
  void set_engine(FusionEngine* engine) { engine_ = engine; }

 private:
  FusionEngine* engine_;
  ObservationId observation_ = 0;
  FeatureId feature_ = 0;
};

// Whether a published feature lies along y = `y`.
bool HasWallAt(const FusionEngine& engine, double y) {
  for (const FusedFeature& f : engine.Published()) {
    if (std::abs(f.fitted.a.y() - y) < 0.05 && std::abs(f.fitted.b.y() - y) < 0.05) return true;
  }
  return false;
}

// Whether a published feature has the ends of `s` (within 0.1 m, either way round).
bool HasFeature(const FusionEngine& engine, const Segment2& s) {
  for (const FusedFeature& f : engine.Published()) {
    const bool same = (f.fitted.a - s.a).norm() < 0.1 && (f.fitted.b - s.b).norm() < 0.1;
    const bool swapped = (f.fitted.a - s.b).norm() < 0.1 && (f.fitted.b - s.a).norm() < 0.1;
    if (same || swapped) return true;
  }
  return false;
}

ClusterId WallIdAt(const FusionEngine& engine, double y) {
  for (const FusedFeature& f : engine.Published()) {
    if (std::abs(f.fitted.a.y() - y) < 0.05) return f.id;
  }
  return 0;
}

FusionParams Params() { return FusionParams(); }  // the defaults: retire_views 10

class WallRetirementTest : public ::testing::Test {
 protected:
  void SetUp() override {
    engine_ = std::make_unique<FusionEngine>(Params());
    robot_ = std::make_unique<Robot>(engine_.get());
    robot_->See({kWall, Vec2Segment()}, 5);  // W and a side wall, both published
    ASSERT_TRUE(HasWallAt(*engine_, 5.0));
  }
  // A side wall that stays: x = -1, from y = 0 to 4 (seen with everything).
  static Segment2 Vec2Segment() { return {Vec2(-1.0, 0.5), Vec2(-1.0, 4.0)}; }

  std::unique_ptr<FusionEngine> engine_;
  std::unique_ptr<Robot> robot_;
};

TEST_F(WallRetirementTest, AWallSeenThroughRetiresAfterRetireViews) {
  const ClusterId w = WallIdAt(*engine_, 5.0);
  const uint32_t views = Params().retire_views;
  ASSERT_EQ(views, 10u);
  // W is gone: the robot sees B through where it stood.
  for (uint32_t i = 1; i < views; ++i) {
    robot_->See({kBehind, Vec2Segment()});
    ASSERT_TRUE(HasWallAt(*engine_, 5.0)) << "retired after only " << i << " views";
  }
  const ChangeFeed feed = robot_->See({kBehind, Vec2Segment()});
  EXPECT_FALSE(HasWallAt(*engine_, 5.0));
  EXPECT_NE(std::find(feed.removed.begin(), feed.removed.end(), w), feed.removed.end())
      << "no removed delta for the retired wall";
  EXPECT_EQ(engine_->retired_count(), 1u);
  EXPECT_FALSE(engine_->GetPublished(w).has_value());
  // The side wall, never seen through, stays.
  EXPECT_TRUE(HasFeature(*engine_, Vec2Segment()));
}

TEST_F(WallRetirementTest, AHiddenWallNeverRetires) {
  // Something now stands between the robot and W: nothing is seen through W.
  robot_->See({kOccluder, Vec2Segment()}, 200);
  EXPECT_TRUE(HasWallAt(*engine_, 5.0));
  EXPECT_EQ(engine_->retired_count(), 0u);
}

TEST_F(WallRetirementTest, ASupportStartsTheCountAgain) {
  // Nine views through, one sighting, nine more: never ten since the last support.
  robot_->See({kBehind, Vec2Segment()}, 9);
  robot_->See({kWall, Vec2Segment()});
  robot_->See({kBehind, Vec2Segment()}, 9);
  EXPECT_TRUE(HasWallAt(*engine_, 5.0));
  robot_->See({kBehind, Vec2Segment()});
  EXPECT_FALSE(HasWallAt(*engine_, 5.0));
}

TEST_F(WallRetirementTest, AWallSeenAgainComesBack) {
  const ClusterId w = WallIdAt(*engine_, 5.0);
  robot_->See({kBehind, Vec2Segment()}, 10);
  ASSERT_FALSE(HasWallAt(*engine_, 5.0));
  // The partition is put back.
  const ChangeFeed feed = robot_->See({kWall, Vec2Segment()});
  EXPECT_TRUE(HasWallAt(*engine_, 5.0));
  EXPECT_NE(std::find(feed.added.begin(), feed.added.end(), w), feed.added.end());
  EXPECT_EQ(engine_->retired_count(), 0u);
  // ... and can go again.
  robot_->See({kBehind, Vec2Segment()}, 10);
  EXPECT_FALSE(HasWallAt(*engine_, 5.0));
}

TEST_F(WallRetirementTest, AWallSeenThroughOnLessThanTheFractionStays) {
  // B seen through x in [1.8, 3.8] of W: 2 m of W's 5 m of cells (its ends
  // trimmed), 40 %, below retire_fraction 0.5, however often.
  const Segment2 through{Vec2(0.6, 10.0), Vec2(4.6, 10.0)};
  robot_->See({through, Vec2Segment()}, 50);
  EXPECT_TRUE(HasWallAt(*engine_, 5.0));
  EXPECT_EQ(engine_->retired_count(), 0u);
  // Seen through over 3 m (60 %): retired.
  robot_->See({Segment2{Vec2(-0.5, 10.0), Vec2(5.5, 10.0)}, Vec2Segment()}, 10);
  EXPECT_FALSE(HasWallAt(*engine_, 5.0));
}

TEST_F(WallRetirementTest, OffWithRetireViewsZero) {
  FusionParams p = Params();
  p.retire_views = 0;
  FusionEngine engine(p);
  Robot robot(&engine);
  robot.See({kWall, Vec2Segment()}, 5);
  robot.See({kBehind, Vec2Segment()}, 50);
  EXPECT_TRUE(HasWallAt(engine, 5.0));
  EXPECT_EQ(engine.retired_count(), 0u);
}

// A snapshot taken part way (some passes counted) and one taken after the
// retirement continue exactly as the live engine.
TEST_F(WallRetirementTest, SnapshotsCarryTheEvidence) {
  robot_->See({kBehind, Vec2Segment()}, 6);
  std::string state;
  ASSERT_TRUE(engine_->SaveState(&state).ok());
  auto restored = FusionEngine::LoadState(Params(), state);
  ASSERT_TRUE(restored.ok()) << restored.status().ToString();
  std::unique_ptr<FusionEngine> other = std::move(*restored);
  Robot twin = *robot_;
  twin.set_engine(other.get());
  for (int i = 0; i < 3; ++i) {
    robot_->See({kBehind, Vec2Segment()});
    twin.See({kBehind, Vec2Segment()});
  }
  EXPECT_TRUE(HasWallAt(*other, 5.0)) << "the restored engine forgot nothing: 9 views";
  robot_->See({kBehind, Vec2Segment()});
  twin.See({kBehind, Vec2Segment()});
  EXPECT_FALSE(HasWallAt(*other, 5.0));
  EXPECT_EQ(other->retired_count(), 1u);
  // And after the retirement: the same bytes, and it still comes back.
  std::string live_state, restored_state;
  ASSERT_TRUE(engine_->SaveState(&live_state).ok());
  ASSERT_TRUE(other->SaveState(&restored_state).ok());
  EXPECT_EQ(live_state, restored_state);
  auto again = FusionEngine::LoadState(Params(), live_state);
  ASSERT_TRUE(again.ok()) << again.status().ToString();
  EXPECT_EQ((*again)->retired_count(), 1u);
  EXPECT_FALSE(HasWallAt(**again, 5.0));
  twin.set_engine(again->get());
  twin.See({kWall, Vec2Segment()});
  EXPECT_TRUE(HasWallAt(**again, 5.0));
}

TEST(WallRetirementParams, OutOfRangeIsRefusedNamingTheField) {
  FusionParams p;
  p.retire_views = 256;
  EXPECT_NE(p.Validate().message().find("retire_views"), std::string::npos);
  for (double fraction : {0.0, -0.1, 1.5, std::nan("")}) {
    FusionParams q;
    q.retire_fraction = fraction;
    EXPECT_NE(q.Validate().message().find("retire_fraction"), std::string::npos) << fraction;
  }
  FusionParams on, off;
  off.retire_views = 0;
  EXPECT_NE(FusionParamsKey(on), FusionParamsKey(off)) << "retirement is not in the snapshot key";
}

TEST(RetirementLedgerCells, TrimmedEndsAndEveryCellCrossed) {
  // 6 m along y = 5.1: trimmed to x in [0.5, 5.5], cells of 0.25 m: 21 columns (2 .. 22).
  const std::vector<uint64_t> cells = RetirementLedger::CellsOf({Vec2(0.0, 5.1), Vec2(6.0, 5.1)});
  EXPECT_EQ(cells.size(), 21u);
  EXPECT_EQ(cells.front(), FreeSpaceGrid::CellKeyOf(Vec2(0.5, 5.1)));
  EXPECT_EQ(cells.back(), FreeSpaceGrid::CellKeyOf(Vec2(5.5, 5.1)));
  // A short piece keeps its middle half.
  EXPECT_EQ(RetirementLedger::CellsOf({Vec2(0.1, 0.1), Vec2(0.9, 0.1)}).size(), 2u);
}

}  // namespace
}  // namespace mapd::fusion::wall_retirement_test
