// A real MapServer on a free loopback port with a real SQLite file, and a
// generated gRPC client to talk to it. Tests read like scripts on top of it.
#ifndef MAPD_TESTS_SERVICE_SERVER_FIXTURE_H_
#define MAPD_TESTS_SERVICE_SERVER_FIXTURE_H_

#include <grpcpp/grpcpp.h>
#include <gtest/gtest.h>

#include <memory>
#include <random>
#include <vector>

#include "common/batches.h"
#include "common/temp_dir.h"
#include "mapserver/v1/map_service.grpc.pb.h"
#include "service/server.h"

namespace mapd::testing {

namespace pb = mapserver::v1;

class ServerFixture : public ::testing::Test {
 protected:
  void SetUp() override {
    Configure();
    StartServer();
  }

  // The test server's settings: a free port, one database in dir_.
  void Configure() {
    config_.listen = "127.0.0.1:0";
    config_.db_path = dir_.File("map.db");
    config_.shutdown_grace_s = 1.0;
    config_.busy_timeout_ms = 300;
  }
  // Several maps instead (--data-dir): dir_ holds one database per map.
  void UseDataDir() {
    config_.db_path.clear();
    config_.data_dir = dir_.path();
  }

  void StartServer() {
    auto server = service::MapServer::Start(config_);
    ASSERT_TRUE(server.ok()) << server.status().ToString();
    server_ = std::move(server).value();
    ASSERT_TRUE(server_->WaitUntilServing(std::chrono::seconds(30))) << "the map was not recovered";
    channel_ = grpc::CreateChannel(server_->address(), grpc::InsecureChannelCredentials());
    stub_ = pb::MapService::NewStub(channel_);
  }

  void Restart() {
    stub_.reset();
    channel_.reset();
    server_.reset();
    StartServer();
  }

  // Sends `batches` on one Ingest stream, half-closes, and returns every ack.
  std::vector<pb::IngestAck> Stream(const std::vector<pb::ObservationBatch>& batches) {
    grpc::ClientContext ctx;
    auto stream = stub_->Ingest(&ctx);
    for (const auto& b : batches) EXPECT_TRUE(stream->Write(b));
    stream->WritesDone();
    std::vector<pb::IngestAck> acks;
    pb::IngestAck ack;
    while (stream->Read(&ack)) acks.push_back(ack);
    const grpc::Status s = stream->Finish();
    EXPECT_TRUE(s.ok()) << s.error_message();
    return acks;
  }

  // `n` batches of robot `robot` walking across the room.
  std::vector<pb::ObservationBatch> Walk(const std::string& robot, int n, uint64_t first_seq = 1,
                                         const std::string& session = "s1") {
    std::vector<pb::ObservationBatch> out;
    for (int i = 0; i < n; ++i) {
      out.push_back(RoomBatch(robot, session, first_seq + static_cast<uint64_t>(i), 2.0 + 0.3 * i,
                              4.0, 0.2 * i, &rng_));
    }
    return out;
  }

  std::vector<pb::FusedFeature> Features(const pb::FeatureMapRequest& request = {}) {
    grpc::ClientContext ctx;
    auto reader = stub_->GetFeatureMap(&ctx, request);
    std::vector<pb::FusedFeature> out;
    pb::FeatureMapPage page;
    while (reader->Read(&page))
      out.insert(out.end(), page.features().begin(), page.features().end());
    last_status_ = reader->Finish();
    return out;
  }

  pb::Stats Stats() {
    grpc::ClientContext ctx;
    pb::Stats stats;
    EXPECT_TRUE(stub_->GetStats(&ctx, {}, &stats).ok());
    return stats;
  }

  TempDir dir_;
  service::ServerConfig config_;
  std::unique_ptr<service::MapServer> server_;
  std::shared_ptr<grpc::Channel> channel_;
  std::unique_ptr<pb::MapService::Stub> stub_;
  grpc::Status last_status_;
  std::mt19937_64 rng_{42};
};

}  // namespace mapd::testing

#endif  // MAPD_TESTS_SERVICE_SERVER_FIXTURE_H_
