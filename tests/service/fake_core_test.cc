// The gRPC handlers on a fake Core (fake_core.h): what they answer when the
// core is recovering, refuses a batch, or lags behind, without making a real
// core do so.
#include "fake_core.h"

#include <gmock/gmock.h>
#include <grpcpp/grpcpp.h>
#include <gtest/gtest.h>

#include <chrono>
#include <memory>
#include <random>
#include <string>
#include <thread>

#include "common/batches.h"
#include "mapserver/v1/map_service.grpc.pb.h"
#include "service/map_service.h"

namespace mapd::testing {
namespace {

namespace pb = mapserver::v1;
using ::testing::HasSubstr;

class FakeCoreTest : public ::testing::Test {
 protected:
  void SetUp() override { served_ = std::make_unique<ServedCore>(&core_); }
  void TearDown() override { served_.reset(); }

  grpc::Status ReadMap(pb::FeatureMapPage* page) {
    grpc::ClientContext ctx;
    auto reader = stub()->GetFeatureMap(&ctx, pb::FeatureMapRequest{});
    while (reader->Read(page)) {
    }
    return reader->Finish();
  }

  // One batch on one Ingest stream: its ack, and the stream's status.
  grpc::Status SendOne(pb::IngestAck* ack) {
    std::mt19937_64 rng(1);
    grpc::ClientContext ctx;
    auto stream = stub()->Ingest(&ctx);
    stream->Write(RoomBatch("r1", "s1", 1, 0, 0, 0, &rng));
    stream->WritesDone();
    while (stream->Read(ack)) {
    }
    return stream->Finish();
  }

  pb::MapService::Stub* stub() const { return served_->stub(); }

  FakeCore core_;
  std::unique_ptr<ServedCore> served_;
};

// The global map builder waits for a recovering core without spinning: it
// asks every 100 ms (a spin asked millions of times a second and took a core
// from the recovery it waited for).
TEST(FakeCoreAlone, TheGlobalMapBuilderWaitsForARecoveringCoreWithoutSpinning) {
  FakeCore core;
  core.SetReady(Status::Unavailable("recovering"));
  {
    ServedCore served(&core);
    const size_t before = core.check_ready_calls();
    std::this_thread::sleep_for(std::chrono::milliseconds(500));
    EXPECT_LT(core.check_ready_calls() - before, 100u);
  }
}

TEST_F(FakeCoreTest, RecoveringCoreRefusesReadsAndBatchesWithUnavailable) {
  core_.SetReady(Status::Unavailable("recovering the fused map: 40% of 1000 observations"));
  pb::FeatureMapPage page;
  const grpc::Status read = ReadMap(&page);
  EXPECT_EQ(read.error_code(), grpc::StatusCode::UNAVAILABLE);
  EXPECT_THAT(read.error_message(), HasSubstr("recovering"));
  pb::IngestAck ack;
  const grpc::Status ingest = SendOne(&ack);
  EXPECT_EQ(ingest.error_code(), grpc::StatusCode::UNAVAILABLE);
  EXPECT_EQ(core_.submitted(), 0u);
}

TEST_F(FakeCoreTest, FeatureMapPageCarriesTheCoresFeaturesVersionAndBacklog) {
  service::FusedView wall;
  wall.feature.id = 7;
  wall.feature.segment = geometry::Segment2{{0, 0}, {4, 0}};
  wall.feature.support = 5;
  wall.robots = {"r1", "r2"};
  core_.features = {wall};
  core_.map_version = 42;
  core_.backlog = 3;
  pb::FeatureMapPage page;
  ASSERT_TRUE(ReadMap(&page).ok());
  EXPECT_EQ(page.total(), 1u);
  EXPECT_EQ(page.map_version(), 42u);
  EXPECT_EQ(page.fusion_pending(), 3u);
  ASSERT_EQ(page.features_size(), 1);
  EXPECT_EQ(page.features(0).id(), 7u);
  EXPECT_DOUBLE_EQ(page.features(0).b().x(), 4.0);
  EXPECT_EQ(page.features(0).robots_size(), 2);
}

TEST_F(FakeCoreTest, BatchTheCoreRefusesIsAckedRejectedWithItsReason) {
  core_.outcome = {service::BatchOutcome::Kind::kRejected,
                   Status::Unavailable("the database refuses writes: disk full")};
  pb::IngestAck ack;
  ASSERT_TRUE(SendOne(&ack).ok());
  EXPECT_EQ(core_.submitted(), 1u);
  EXPECT_EQ(ack.result(), pb::IngestAck::REJECTED);
  EXPECT_EQ(ack.code(), static_cast<int>(grpc::StatusCode::UNAVAILABLE));
  EXPECT_THAT(ack.message(), HasSubstr("disk full"));
}

}  // namespace
}  // namespace mapd::testing
