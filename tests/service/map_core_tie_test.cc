// MapCore ties session frames incrementally: the newly tied sessions' stored
// observations are added to the running engine. In exact mode (order
// independent) the result must equal a full rebuild from the database.
#include "service/map_core.h"

#include <future>
#include <random>

#include <gtest/gtest.h>

#include "common/batches.h"
#include "common/temp_dir.h"
#include "service/ingest_batch.h"

namespace mapd::service {
namespace {

namespace pb = mapserver::v1;
using mapd::testing::RoomBatch;
using mapd::testing::TempDir;

class MapCoreTieTest : public ::testing::Test {
 protected:
  void SetUp() override {
    options_.db_path = dir_.File("map.db");
    options_.fusion.mode = fusion::FusionMode::kExact;
    options_.fusion.min_support = 2;
    Open();
  }

  void Open() {
    StatusOr<std::unique_ptr<MapCore>> core = MapCore::Open(options_);
    ASSERT_TRUE(core.ok()) << core.status().ToString();
    core_ = std::move(core).value();
    ASSERT_TRUE(core_->WaitUntilReady(std::chrono::seconds(30)));
  }

  // Streams `count` room batches of `robot` from (5, 4) in the map frame;
  // LOCAL ones report their poses in a frame shifted by (dx, 0), so that
  // T_map_frame is a translation by (-dx, 0).
  void Stream(const std::string& robot, bool local, double dx, int count, uint64_t seed) {
    std::mt19937_64 rng(seed);
    for (int k = 0; k < count; ++k) {
      pb::ObservationBatch b = RoomBatch(robot, "s", static_cast<uint64_t>(k) + 1, 5, 4, 0.3 * k, &rng);
      if (local) {
        b.set_session_frame(pb::SESSION_FRAME_LOCAL);
        b.mutable_t_frame_sensor()->mutable_translation()->set_x(5 + dx);
      }
      StatusOr<IngestBatch> batch = ValidateBatch(b, IngestLimits());
      ASSERT_TRUE(batch.ok()) << batch.status().ToString();
      std::promise<BatchOutcome> done;
      core_->Submit(*batch, [&](const BatchOutcome& o) { done.set_value(o); });
      ASSERT_EQ(done.get_future().get().kind, BatchOutcome::Kind::kStored);
    }
  }

  std::vector<FusedView> Map() { return core_->QueryFeatures(FeatureQuery(), nullptr); }

  TempDir dir_;
  MapCoreOptions options_;
  std::unique_ptr<MapCore> core_;
};

TEST_F(MapCoreTieTest, TieAddsTheSessionAndEqualsAFullRebuild) {
  Stream("r1", false, 0.0, 8, 1);
  Stream("r2", true, 2.0, 8, 2);  // r2's frame is the map frame shifted by 2 m
  const std::vector<FusedView> before = Map();
  ASSERT_EQ(before.size(), 4u);
  for (const FusedView& f : before) EXPECT_EQ(f.robots, std::vector<std::string>{"r1"});

  StatusOr<storage::SessionFrame> r2 = core_->store().FindSession("r2", "s");
  ASSERT_TRUE(r2.ok());
  geometry::Rigid3 T_map_r2 = geometry::Rigid3::Identity();
  T_map_r2.translation = Eigen::Vector3d(-2.0, 0.0, 0.0);
  ASSERT_TRUE(core_->ExecuteWrite([&](storage::WriteTransaction* txn) {
                 return txn->TieSession(r2->session_id, T_map_r2);
               }).ok());
  const std::vector<FusedView> tied = Map();
  ASSERT_EQ(tied.size(), 4u);
  for (const FusedView& f : tied) {
    EXPECT_EQ(f.robots, (std::vector<std::string>{"r1", "r2"}));
    EXPECT_EQ(f.feature.support, 16u);
  }

  // A restart rebuilds from scratch: the same map, to rounding.
  core_->Stop();
  core_.reset();
  Open();
  const std::vector<FusedView> rebuilt = Map();
  ASSERT_EQ(rebuilt.size(), tied.size());
  for (size_t i = 0; i < tied.size(); ++i) {
    EXPECT_EQ(rebuilt[i].feature.id, tied[i].feature.id);
    EXPECT_EQ(rebuilt[i].feature.support, tied[i].feature.support);
    EXPECT_EQ(rebuilt[i].feature.member_count, tied[i].feature.member_count);
    EXPECT_LE((rebuilt[i].feature.segment.a - tied[i].feature.segment.a).norm(), 1e-9);
    EXPECT_LE((rebuilt[i].feature.segment.b - tied[i].feature.segment.b).norm(), 1e-9);
  }
}

}  // namespace
}  // namespace mapd::service
