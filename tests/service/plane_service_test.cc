// Non-vertical planes end to end: batches with floors and ceilings through
// Ingest, fused planes served by GetFeatureMap (filters included), and kept
// across a restart (from the snapshot, not a replay).
#include <gtest/gtest.h>
#include <sqlite3.h>

#include "server_fixture.h"
#include "storage/sqlite/store.h"
#include "storage/store.h"

namespace mapd::testing {
namespace {

// A batch with an identity sensor pose: the floor (z = 0) and the ceiling
// (z = 2.5) of a 10 m x 8 m room, each seen a little differently per seq.
pb::ObservationBatch FloorAndCeiling(const std::string& robot, uint64_t seq) {
  pb::ObservationBatch b;
  b.set_robot_id(robot);
  b.set_session_id("s1");
  b.set_seq(seq);
  b.set_stamp_ns(static_cast<int64_t>(seq) * 100000000);
  b.mutable_t_frame_sensor()->mutable_rotation()->set_w(1);
  b.mutable_t_frame_sensor()->mutable_translation();
  const double d = 0.1 * static_cast<double>(seq % 3);
  for (double z : {0.0, 2.5}) {
    auto* p = b.add_planes();
    // The ceiling's normal points down, as a sensor below it sees it.
    p->mutable_normal()->set_z(z == 0.0 ? 1 : -1);
    p->set_offset(z == 0.0 ? 0 : 2.5);
    for (auto [x, y] : {std::pair{d, d}, {10.0 - d, 0.0}, {10.0, 8.0 - d}, {0.0, 8.0}}) {
      auto* q = p->add_boundary();
      q->set_x(x);
      q->set_y(y);
      q->set_z(z);
    }
  }
  return b;
}

class PlaneServiceTest : public ServerFixture {
 protected:
  std::vector<pb::FusedPlane> Planes(const pb::FeatureMapRequest& request = {}) {
    grpc::ClientContext ctx;
    auto reader = stub_->GetFeatureMap(&ctx, request);
    std::vector<pb::FusedPlane> out;
    pb::FeatureMapPage page;
    while (reader->Read(&page)) out.insert(out.end(), page.planes().begin(), page.planes().end());
    last_status_ = reader->Finish();
    return out;
  }
};

TEST_F(PlaneServiceTest, FloorAndCeilingFromThreeObservationsAreServed) {
  Stream({FloorAndCeiling("r1", 1), FloorAndCeiling("r2", 2)});
  EXPECT_TRUE(Planes().empty()) << "two observations are below planes.min_support";
  Stream({FloorAndCeiling("r1", 3)});
  const auto planes = Planes();
  ASSERT_TRUE(last_status_.ok()) << last_status_.error_message();
  ASSERT_EQ(planes.size(), 2u);
  EXPECT_EQ(Stats().fused_planes(), 2u);
  const pb::FusedPlane& floor = planes[0].z_max() < 1 ? planes[0] : planes[1];
  const pb::FusedPlane& ceiling = planes[0].z_max() < 1 ? planes[1] : planes[0];
  EXPECT_NEAR(floor.normal().z(), 1.0, 1e-9);
  EXPECT_NEAR(floor.offset(), 0.0, 1e-9);
  EXPECT_NEAR(ceiling.normal().z(), 1.0, 1e-9);  // canonical sign: up
  EXPECT_NEAR(ceiling.offset(), -2.5, 1e-9);
  EXPECT_NEAR(floor.area(), 80.0, 1e-6);
  EXPECT_EQ(floor.support(), 3u);
  EXPECT_EQ(floor.member_count(), 3u);
  ASSERT_EQ(floor.robots_size(), 2);
  EXPECT_EQ(floor.robots(0), "r1");
  EXPECT_EQ(floor.robots(1), "r2");
  EXPECT_GE(floor.boundary_size(), 4);

  pb::FeatureMapRequest lines_only;
  lines_only.set_kind(pb::FEATURE_KIND_LINE);
  EXPECT_TRUE(Planes(lines_only).empty());
  pb::FeatureMapRequest inside;  // a box inside the room meets both
  inside.mutable_bbox()->mutable_min()->set_x(4);
  inside.mutable_bbox()->mutable_min()->set_y(4);
  inside.mutable_bbox()->mutable_max()->set_x(5);
  inside.mutable_bbox()->mutable_max()->set_y(5);
  EXPECT_EQ(Planes(inside).size(), 2u);
  pb::FeatureMapRequest outside;
  outside.mutable_bbox()->mutable_min()->set_x(11);
  outside.mutable_bbox()->mutable_min()->set_y(0);
  outside.mutable_bbox()->mutable_max()->set_x(12);
  outside.mutable_bbox()->mutable_max()->set_y(1);
  EXPECT_TRUE(Planes(outside).empty());
  pb::FeatureMapRequest more_support;
  more_support.set_min_support(4);
  EXPECT_TRUE(Planes(more_support).empty());
}

TEST_F(PlaneServiceTest, ARestartKeepsTheFusedPlanesWithoutAReplay) {
  Stream({FloorAndCeiling("r1", 1), FloorAndCeiling("r2", 2), FloorAndCeiling("r1", 3)});
  const auto before = Planes();
  ASSERT_EQ(before.size(), 2u);
  Restart();
  EXPECT_EQ(Stats().replay_length(), 0u) << "the stop's snapshot holds the plane engine too";
  const auto after = Planes();
  ASSERT_EQ(after.size(), before.size());
  for (size_t i = 0; i < after.size(); ++i)
    EXPECT_EQ(after[i].DebugString(), before[i].DebugString());
  // And the restored engine goes on fusing.
  Stream({FloorAndCeiling("r2", 4)});
  const auto more = Planes();
  ASSERT_EQ(more.size(), 2u);
  EXPECT_EQ(more[0].support(), 4u);
}

TEST_F(PlaneServiceTest, FusedPlanesArePersistedAndASnapshotWithoutPlanesIsReplayedPast) {
  Stream({FloorAndCeiling("r1", 1), FloorAndCeiling("r2", 2), FloorAndCeiling("r1", 3)});
  const auto before = Planes();
  ASSERT_EQ(before.size(), 2u);
  stub_.reset();
  server_.reset();
  {
    auto store = storage::SqliteStore::Open(config_.db_path, {});
    ASSERT_TRUE(store.ok()) << store.status().ToString();
    auto rows = (*store)->LoadFusedPlanes();
    ASSERT_TRUE(rows.ok());
    ASSERT_EQ(rows->size(), 2u);
    for (size_t i = 0; i < rows->size(); ++i) {
      EXPECT_EQ((*rows)[i].id, before[i].id());
      EXPECT_EQ((*rows)[i].support, 3u);
      EXPECT_EQ((*rows)[i].robots, "r1,r2");
      EXPECT_NEAR((*rows)[i].offset_m, before[i].offset(), 1e-12);
    }
  }
  // As if the snapshots predated plane fusion (schema 4).
  sqlite3* db = nullptr;
  ASSERT_EQ(sqlite3_open(config_.db_path.c_str(), &db), SQLITE_OK);
  ASSERT_EQ(
      sqlite3_exec(db, "UPDATE fusion_snapshots SET plane_state = NULL", nullptr, nullptr, nullptr),
      SQLITE_OK);
  sqlite3_close(db);
  StartServer();
  const auto after = Planes();
  ASSERT_EQ(after.size(), before.size());
  for (size_t i = 0; i < after.size(); ++i)
    EXPECT_EQ(after[i].DebugString(), before[i].DebugString());
}

}  // namespace
}  // namespace mapd::testing
