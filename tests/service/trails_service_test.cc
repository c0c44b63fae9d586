// GetTrails through the real server: each session's sensor positions in seq
// order, in the map frame where the session is tied (at ingest, or later by a
// tie such as a merge makes), thinned on request, filtered by robot; a bad
// robot id is refused.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "server_fixture.h"
#include "storage/sqlite/store.h"
#include "storage/store.h"

namespace mapd::testing {
namespace {

using ::testing::HasSubstr;

class TrailsTest : public ServerFixture {
 protected:
  std::vector<pb::SessionTrail> Trails(const pb::GetTrailsRequest& request = {}) {
    grpc::ClientContext ctx;
    auto reader = stub_->GetTrails(&ctx, request);
    std::vector<pb::SessionTrail> out;
    pb::SessionTrail t;
    while (reader->Read(&t)) out.push_back(t);
    last_status_ = reader->Finish();
    return out;
  }

  // r1 walks 10 poses in the map frame; r2 3 poses in its own (local) frame.
  void StreamTwoRobots() {
    ASSERT_EQ(Stream(Walk("r1", 10)).size(), 10u);
    std::vector<pb::ObservationBatch> local = Walk("r2", 3, 1, "local");
    for (pb::ObservationBatch& b : local) b.set_session_frame(pb::SESSION_FRAME_LOCAL);
    ASSERT_EQ(Stream(local).size(), 3u);
  }
};

TEST_F(TrailsTest, OneTrailPerSessionInSeqOrderWithItsFrame) {
  StreamTwoRobots();
  const std::vector<pb::SessionTrail> trails = Trails();
  ASSERT_TRUE(last_status_.ok()) << last_status_.error_message();
  ASSERT_EQ(trails.size(), 2u);
  const pb::SessionTrail& r1 = trails[0];
  EXPECT_EQ(r1.robot_id(), "r1");
  EXPECT_EQ(r1.session_id(), "s1");
  EXPECT_TRUE(r1.frame_tied());
  EXPECT_EQ(r1.stored_poses(), 10u);
  ASSERT_EQ(r1.poses_size(), 10);
  for (int i = 0; i < 10; ++i) {
    EXPECT_EQ(r1.poses(i).seq(), static_cast<uint64_t>(i + 1));
    EXPECT_EQ(r1.poses(i).stamp_ns(), (i + 1) * 100000000LL);
    EXPECT_NEAR(r1.poses(i).position().x(), 2.0 + 0.3 * i, 1e-9);  // Walk's path
    EXPECT_NEAR(r1.poses(i).position().y(), 4.0, 1e-9);
  }
  const pb::SessionTrail& r2 = trails[1];
  EXPECT_EQ(r2.robot_id(), "r2");
  EXPECT_EQ(r2.session_id(), "local");
  EXPECT_FALSE(r2.frame_tied());  // its own frame until a merge ties it
  ASSERT_EQ(r2.poses_size(), 3);
  EXPECT_NEAR(r2.poses(2).position().x(), 2.6, 1e-9);
}

TEST_F(TrailsTest, ThinsLongSessionsKeepingTheEndsAndFiltersByRobot) {
  StreamTwoRobots();
  pb::GetTrailsRequest request;
  request.set_max_poses_per_session(4);
  std::vector<pb::SessionTrail> trails = Trails(request);
  ASSERT_EQ(trails.size(), 2u);
  EXPECT_EQ(trails[0].stored_poses(), 10u);
  ASSERT_GE(trails[0].poses_size(), 2);
  EXPECT_LE(trails[0].poses_size(), 4);
  EXPECT_EQ(trails[0].poses(0).seq(), 1u);
  EXPECT_EQ(trails[0].poses(trails[0].poses_size() - 1).seq(), 10u);
  EXPECT_EQ(trails[1].poses_size(), 3);  // short enough: whole

  request.set_max_poses_per_session(1);  // raised to 2: both ends
  trails = Trails(request);
  ASSERT_EQ(trails.size(), 2u);
  ASSERT_EQ(trails[0].poses_size(), 2);
  EXPECT_EQ(trails[0].poses(1).seq(), 10u);

  request = {};
  request.set_robot_id("r2");
  trails = Trails(request);
  ASSERT_EQ(trails.size(), 1u);
  EXPECT_EQ(trails[0].robot_id(), "r2");
  request.set_robot_id("nobody");
  EXPECT_TRUE(Trails(request).empty());
  EXPECT_TRUE(last_status_.ok());
}

TEST_F(TrailsTest, BadRobotIdIsRefused) {
  pb::GetTrailsRequest request;
  request.set_robot_id("no spaces!");
  EXPECT_TRUE(Trails(request).empty());
  EXPECT_EQ(last_status_.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_THAT(last_status_.error_message(), HasSubstr("robot_id"));
}

TEST_F(TrailsTest, TiedSessionComesInTheMapFrame) {
  StreamTwoRobots();
  // Tie r2's frame as an accepted merge would: a quarter turn, then a shift.
  stub_.reset();
  channel_.reset();
  server_.reset();
  {
    StatusOr<std::unique_ptr<storage::SqliteStore>> store =
        storage::SqliteStore::Open(config_.db_path, storage::StoreOptions());
    ASSERT_TRUE(store.ok()) << store.status().ToString();
    StatusOr<storage::SessionFrame> local = (*store)->FindSession("r2", "local");
    ASSERT_TRUE(local.ok());
    geometry::Rigid3 T_map_frame;
    T_map_frame.rotation =
        Eigen::Quaterniond(Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitZ()));
    T_map_frame.translation = {1.0, 2.0, 0.0};
    auto txn = (*store)->BeginWrite();
    ASSERT_TRUE(txn.ok());
    ASSERT_TRUE((*txn)->TieSession(local->session_id, T_map_frame).ok());
    ASSERT_TRUE((*txn)->Commit().ok());
  }
  StartServer();
  pb::GetTrailsRequest request;
  request.set_robot_id("r2");
  const std::vector<pb::SessionTrail> trails = Trails(request);
  ASSERT_EQ(trails.size(), 1u);
  EXPECT_TRUE(trails[0].frame_tied());
  ASSERT_EQ(trails[0].poses_size(), 3);
  // (2.6, 4.0) in the session frame -> (1 - 4.0, 2 + 2.6) in the map frame.
  EXPECT_NEAR(trails[0].poses(2).position().x(), -3.0, 1e-9);
  EXPECT_NEAR(trails[0].poses(2).position().y(), 4.6, 1e-9);
}

}  // namespace
}  // namespace mapd::testing
