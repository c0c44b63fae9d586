// The service end to end, in process: ingest, duplicates, bad input, queries,
// restart. (The SIGKILL crash test with the real binary is crash_restart_test.cc.)
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <sqlite3.h>

#include <chrono>
#include <cmath>
#include <memory>
#include <thread>
#include <vector>

#include "common/health.h"
#include "server_fixture.h"
#include "service/merge_runner.h"
#include "service/voxel_merge.h"

namespace mapd::testing {
namespace {

using ::testing::HasSubstr;

int Count(const std::vector<pb::IngestAck>& acks, pb::IngestAck::Result r) {
  int n = 0;
  for (const auto& a : acks) n += a.result() == r;
  return n;
}

TEST_F(ServerFixture, AcknowledgesEveryBatchAsStoredAndFusesTheRoom) {
  const auto acks = Stream(Walk("r1", 12));
  ASSERT_EQ(acks.size(), 12u);
  EXPECT_EQ(Count(acks, pb::IngestAck::STORED), 12);
  const auto features = Features();
  // Four walls, each seen in 12 observations: exactly four fused features.
  ASSERT_EQ(features.size(), 4u);
  for (const auto& f : features) {
    EXPECT_EQ(f.support(), 12u);
    EXPECT_EQ(f.kind(), pb::FEATURE_KIND_LINE);
    EXPECT_THAT(f.robots(), ::testing::ElementsAre("r1"));
  }
  const pb::Stats stats = Stats();
  EXPECT_EQ(stats.batches(), 12u);
  EXPECT_EQ(stats.raw_features(), 48u);
  EXPECT_EQ(stats.fused_features(), 4u);
  EXPECT_EQ(stats.robots(), 1u);
  EXPECT_GT(stats.db_size_bytes(), 0u);
}

TEST_F(ServerFixture, CornersOfTheFusedRoomLandOnTheTrueCorners) {
  Stream(Walk("r1", 12));
  const std::vector<Eigen::Vector2d> corners = {{0, 0}, {10, 0}, {10, 8}, {0, 8}};
  const std::vector<pb::FusedFeature> walls = Features();
  ASSERT_EQ(walls.size(), 4u) << "the room has four walls";
  // Each wall's endpoints are two different true corners, and together the
  // four walls' eight endpoints hit every corner twice.
  std::vector<int> hits(corners.size(), 0);
  for (const auto& f : walls) {
    std::vector<size_t> ends;
    for (const auto& p : {f.a(), f.b()}) {
      size_t best = 0;
      for (size_t c = 1; c < corners.size(); ++c) {
        if ((Eigen::Vector2d(p.x(), p.y()) - corners[c]).norm() <
            (Eigen::Vector2d(p.x(), p.y()) - corners[best]).norm())
          best = c;
      }
      EXPECT_LT((Eigen::Vector2d(p.x(), p.y()) - corners[best]).norm(), 0.05)
          << "endpoint (" << p.x() << ", " << p.y() << ") far from every corner";
      ++hits[best];
      ends.push_back(best);
    }
    EXPECT_NE(ends[0], ends[1]) << f.ShortDebugString();
  }
  for (size_t c = 0; c < corners.size(); ++c)
    EXPECT_EQ(hits[c], 2) << "corner (" << corners[c].x() << ", " << corners[c].y() << ")";
}

TEST_F(ServerFixture, ResentBatchesAreDuplicatesAndNotAppliedTwice) {
  const auto batches = Walk("r1", 6);
  Stream(batches);
  const auto before = Features();
  const auto acks = Stream(batches);  // a robot reconnecting and resending everything
  EXPECT_EQ(Count(acks, pb::IngestAck::DUPLICATE), 6);
  EXPECT_EQ(Stats().batches(), 6u);
  const auto after = Features();
  ASSERT_EQ(after.size(), before.size());
  for (size_t i = 0; i < after.size(); ++i) EXPECT_EQ(after[i].support(), before[i].support());
}

TEST_F(ServerFixture, ABadBatchIsRejectedAndTheStreamGoesOn) {
  auto batches = Walk("r1", 5);
  batches[2].mutable_lines(1)->mutable_a()->set_x(std::nan(""));
  batches[3].mutable_t_frame_sensor()->mutable_rotation()->set_w(3.0);
  const auto acks = Stream(batches);
  ASSERT_EQ(acks.size(), 5u);
  std::map<uint64_t, pb::IngestAck> by_seq;
  for (const auto& a : acks) by_seq[a.seq()] = a;
  EXPECT_EQ(by_seq[1].result(), pb::IngestAck::STORED);
  EXPECT_EQ(by_seq[3].result(), pb::IngestAck::REJECTED);
  EXPECT_EQ(by_seq[3].code(), static_cast<int>(grpc::StatusCode::INVALID_ARGUMENT));
  EXPECT_THAT(by_seq[3].message(), HasSubstr("lines[1].a.x is NaN"));
  EXPECT_EQ(by_seq[4].result(), pb::IngestAck::REJECTED);
  EXPECT_THAT(by_seq[4].message(), HasSubstr("rotation"));
  EXPECT_EQ(by_seq[5].result(), pb::IngestAck::STORED);
  EXPECT_EQ(Stats().batches(), 3u);  // nothing of the bad ones was stored
}

TEST_F(ServerFixture, AnOverLimitBatchIsResourceExhausted) {
  auto batch = Walk("r1", 1)[0];
  for (int i = 0; i < 1100; ++i) *batch.add_lines() = batch.lines(0);
  const auto acks = Stream({batch});
  ASSERT_EQ(acks.size(), 1u);
  EXPECT_EQ(acks[0].result(), pb::IngestAck::REJECTED);
  EXPECT_EQ(acks[0].code(), static_cast<int>(grpc::StatusCode::RESOURCE_EXHAUSTED));
  EXPECT_THAT(acks[0].message(), HasSubstr("max_features_per_batch"));
}

TEST_F(ServerFixture, BadInputFromOneRobotDoesNotDisturbAnother) {
  Stream(Walk("good", 6));
  const auto before = Features();
  auto bad = Walk("bad", 3, 1, "x");
  for (auto& b : bad) b.mutable_lines(0)->mutable_b()->set_y(INFINITY);
  Stream(bad);
  const auto after = Features();
  ASSERT_EQ(after.size(), before.size());
  for (size_t i = 0; i < after.size(); ++i)
    EXPECT_EQ(after[i].DebugString(), before[i].DebugString());
  EXPECT_EQ(Stats().robots(), 1u);
}

TEST_F(ServerFixture, TwoRobotsFeedOneMap) {
  Stream(Walk("r1", 4));
  Stream(Walk("r2", 4));
  const auto features = Features();
  ASSERT_EQ(features.size(), 4u);
  for (const auto& f : features) {
    EXPECT_EQ(f.support(), 8u);
    EXPECT_THAT(f.robots(), ::testing::ElementsAre("r1", "r2"));
  }
}

TEST_F(ServerFixture, AFrameKindChangeWithinASessionIsRejected) {
  Stream(Walk("r1", 2));
  auto b = Walk("r1", 1, 3)[0];
  b.set_session_frame(pb::SESSION_FRAME_LOCAL);
  const auto acks = Stream({b});
  ASSERT_EQ(acks.size(), 1u);
  EXPECT_EQ(acks[0].result(), pb::IngestAck::REJECTED);
  EXPECT_THAT(acks[0].message(), HasSubstr("session_frame"));
}

TEST_F(ServerFixture, LocalFrameSessionsAreStoredButNotFusedUntilTied) {
  auto batches = Walk("r1", 6);
  for (auto& b : batches) b.set_session_frame(pb::SESSION_FRAME_LOCAL);
  EXPECT_EQ(Count(Stream(batches), pb::IngestAck::STORED), 6);
  EXPECT_TRUE(Features().empty());
  EXPECT_EQ(Stats().batches(), 6u);
}

TEST_F(ServerFixture, QueriesFilterByBoxSupportAndKind) {
  Stream(Walk("r1", 8));
  pb::FeatureMapRequest only_bottom;
  only_bottom.mutable_bbox()->mutable_min()->set_x(2);
  only_bottom.mutable_bbox()->mutable_min()->set_y(-1);
  only_bottom.mutable_bbox()->mutable_max()->set_x(8);
  only_bottom.mutable_bbox()->mutable_max()->set_y(1);
  EXPECT_EQ(Features(only_bottom).size(), 1u);  // the wall along y = 0

  pb::FeatureMapRequest high_support;
  high_support.set_min_support(9);
  EXPECT_TRUE(Features(high_support).empty());

  pb::FeatureMapRequest planes;
  planes.set_kind(pb::FEATURE_KIND_PLANE);
  EXPECT_TRUE(Features(planes).empty());

  pb::FeatureMapRequest inverted;
  inverted.mutable_bbox()->mutable_min()->set_x(5);
  inverted.mutable_bbox()->mutable_max()->set_x(1);
  Features(inverted);
  EXPECT_EQ(last_status_.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
}

TEST_F(ServerFixture, VerticalPlanesBecomePlaneFeatures) {
  std::vector<pb::ObservationBatch> batches = Walk("r1", 4);
  for (auto& b : batches) {
    b.clear_lines();
    b.clear_t_frame_sensor();
    b.mutable_t_frame_sensor()->mutable_rotation()->set_w(1);
    b.mutable_t_frame_sensor()->mutable_translation();
    // The wall x = 10 as a plane: normal (1, 0, 0), offset -10, spanning y 1..7, z 0..2.5.
    auto* p = b.add_planes();
    p->mutable_normal()->set_x(1);
    p->set_offset(-10);
    for (auto [y, z] : {std::pair{1.0, 0.0}, {7.0, 0.0}, {7.0, 2.5}, {1.0, 2.5}}) {
      auto* q = p->add_boundary();
      q->set_x(10);
      q->set_y(y + 0.01 * static_cast<double>(b.seq()));
      q->set_z(z);
    }
  }
  Stream(batches);
  pb::FeatureMapRequest planes;
  planes.set_kind(pb::FEATURE_KIND_PLANE);
  const auto features = Features(planes);
  ASSERT_EQ(features.size(), 1u);
  EXPECT_NEAR(features[0].a().x(), 10.0, 1e-9);
  EXPECT_NEAR(features[0].z_max(), 2.5, 1e-9);
}

TEST_F(ServerFixture, ARestartedServerServesTheSameMap) {
  Stream(Walk("r1", 10));
  Stream(Walk("r2", 5));
  const auto before = Features();
  const auto stats_before = Stats();
  Restart();
  const auto after = Features();
  ASSERT_EQ(after.size(), before.size());
  for (size_t i = 0; i < after.size(); ++i)
    EXPECT_EQ(after[i].DebugString(), before[i].DebugString());
  EXPECT_EQ(Stats().batches(), stats_before.batches());
  // A robot resending after the restart is recognised: (robot, session, seq) is the key.
  EXPECT_EQ(Count(Stream(Walk("r1", 3)), pb::IngestAck::DUPLICATE), 3);
}

TEST_F(ServerFixture, ALockedDatabaseRefusesBatchesRetryablyAndLosesNothing) {
  Stream(Walk("r1", 5));
  const auto before = Features();
  Restart();  // with a short busy timeout
  // Another process (an operator's sqlite3 shell, a backup) holds the write lock.
  sqlite3* other = nullptr;
  ASSERT_EQ(sqlite3_open(config_.db_path.c_str(), &other), SQLITE_OK);
  ASSERT_EQ(sqlite3_exec(other, "BEGIN EXCLUSIVE", nullptr, nullptr, nullptr), SQLITE_OK);
  const auto refused = Stream(Walk("r1", 3, 6));
  ASSERT_EQ(refused.size(), 3u);
  for (const auto& a : refused) {
    EXPECT_EQ(a.result(), pb::IngestAck::REJECTED);
    EXPECT_EQ(a.code(), static_cast<int>(grpc::StatusCode::UNAVAILABLE));
    EXPECT_THAT(a.message(), HasSubstr("resend"));
  }
  // Meanwhile the server says why it does not take writes (and health says
  // NOT_SERVING), and refuses batches at once rather than queueing them.
  EXPECT_THAT(Stats().write_failure(), HasSubstr("database is locked"));
  sqlite3_exec(other, "ROLLBACK", nullptr, nullptr, nullptr);
  sqlite3_close(other);
  // Its probe (at most a second apart) finds the lock gone.
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(20);
  while (!Stats().write_failure().empty() && std::chrono::steady_clock::now() < deadline) {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  EXPECT_EQ(Stats().write_failure(), "");
  // The server is still up, the earlier map intact, and the resend is stored.
  EXPECT_EQ(Count(Stream(Walk("r1", 3, 6)), pb::IngestAck::STORED), 3);
  EXPECT_EQ(Stats().batches(), 8u);
  EXPECT_EQ(Features().size(), before.size());
}

// Submap RPCs answer in every build (merges of stored submaps are covered by
// tests/service/submap_service_test.cc where the voxel library is built).
TEST_F(ServerFixture, SubmapRpcsAnswerInEveryBuild) {
  grpc::ClientContext ctx;
  pb::ListSubmapsResponse resp;
  ASSERT_TRUE(stub_->ListSubmaps(&ctx, {}, &resp).ok());
  EXPECT_EQ(resp.submaps_size(), 0);
  grpc::ClientContext merge_ctx;
  pb::MergeSubmapsRequest request;
  request.add_submap_ids(1);
  request.add_submap_ids(2);
  auto reader = stub_->MergeSubmaps(&merge_ctx, request);
  pb::MergeProgress progress;
  while (reader->Read(&progress)) {
  }
  const grpc::Status s = reader->Finish();
  EXPECT_EQ(s.error_code(), grpc::StatusCode::NOT_FOUND) << s.error_message();
}

// The one switch (service/voxel_merge.h): without the voxel library a merge is
// refused before anything runs, with a message naming the build option.
TEST(VoxelMergeSwitchTest, TheRunnerRefusesMergesOnlyWhenMergingIsNotBuilt) {
  EXPECT_EQ(service::VoxelMergeBuilt(), MAPD_TEST_WITH_VOXEL == 1);
  service::MergeRunner runner(1, 1);
  StatusOr<std::shared_ptr<service::MergeJob>> job =
      runner.Submit(runner.NewOwner(), {1, 2}, {"", ""}, {});
  if (service::VoxelMergeBuilt()) {
    ASSERT_TRUE(job.ok()) << job.status().ToString();
    std::vector<service::MergeProgressEvent> events;
    while (!(*job)->Wait(std::chrono::milliseconds(50), &events)) {
    }
    EXPECT_EQ((*job)->TakeResult().status().code(), StatusCode::kInvalidArgument);  // empty files
  } else {
    EXPECT_EQ(job.status().code(), StatusCode::kUnimplemented);
    EXPECT_THAT(job.status().message(), HasSubstr("MAPD_WITH_VOXEL=OFF"));
  }
}

TEST_F(ServerFixture, HealthServiceReportsServing) {
  // Health turns SERVING just after recovery ends, on another thread: under a
  // sanitizer the first check can come before it (CI, 2026-12-04).
  Health health = CheckHealth(channel_);
  for (int i = 0; i < 200 && health != Health::kServing; ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
    health = CheckHealth(channel_);
  }
  EXPECT_EQ(health, Health::kServing);
}

}  // namespace
}  // namespace mapd::testing
