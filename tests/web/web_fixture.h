// A real MapServer (gRPC, SQLite) with a WebServer beside it on a free
// loopback port, an httplib client for the web side and a gRPC stub to
// ingest. Shared by the web view's tests.
#ifndef MAPD_TESTS_WEB_WEB_FIXTURE_H_
#define MAPD_TESTS_WEB_WEB_FIXTURE_H_

#include <grpcpp/grpcpp.h>
#include <gtest/gtest.h>

#include <memory>
#include <nlohmann/json.hpp>
#include <random>
#include <string>
#include <vector>

#include "common/batches.h"
#include "common/temp_dir.h"
#include "mapserver/v1/map_service.grpc.pb.h"
#include "service/server.h"
#include "service/token.h"
#include "storage/store.h"
#include "web/http.h"
#include "web/web_server.h"

namespace mapd::testing {

namespace pb = mapserver::v1;
using nlohmann::json;

// `n` batches of the 10 m x 8 m room (tests/common/batches.h) from `robot`,
// seen from (x, y).
inline std::vector<pb::ObservationBatch> RoomBatches(const std::string& robot, int n, double x = 3,
                                                     double y = 2, uint64_t first_seq = 1) {
  std::mt19937_64 rng(7);
  std::vector<pb::ObservationBatch> out;
  for (int i = 0; i < n; ++i)
    out.push_back(RoomBatch(robot, "s1", first_seq + i, x + 0.1 * i, y, 0.2 * i, &rng));
  return out;
}

// `n` batches seeing one wall from (20, 0) to (26, 0) from the origin of the map.
inline std::vector<pb::ObservationBatch> FarWallBatches(const std::string& robot, int n) {
  std::vector<pb::ObservationBatch> out;
  for (int i = 0; i < n; ++i) {
    pb::ObservationBatch b;
    b.set_robot_id(robot);
    b.set_session_id("far");
    b.set_seq(static_cast<uint64_t>(i + 1));
    b.set_stamp_ns((i + 1) * 100000000LL);
    b.mutable_t_frame_sensor()->mutable_rotation()->set_w(1);
    b.mutable_t_frame_sensor()->mutable_translation()->set_x(20);
    auto* line = b.add_lines();
    SetVec3({0.2 + 0.01 * i, 3, 0}, line->mutable_a());
    SetVec3({5.8 - 0.01 * i, 3, 0}, line->mutable_b());
    out.push_back(b);
  }
  return out;
}

// A proposed merge of submaps 1 and 2 as a merge run records one (proposals
// need the voxel library): submap 2 placed by the correlation generator, its
// runner-up not measured. The merged map's bytes are never read.
inline storage::NewMerge ProposedMerge() {
  storage::NewMerge m;
  m.record.state = storage::MergeState::kProposed;
  m.record.created_ns = 1;
  m.record.requested_by = "test";
  m.merged.meta.robot = storage::kMergedRobot;
  m.merged.meta.name = "proposal";
  m.merged.meta.resolution_m = 0.1;
  m.merged.data = "not a map: never read";
  storage::MergeInputRecord reference, placed;
  reference.submap_id = 1;
  reference.aligned = true;
  placed.submap_id = 2;
  placed.aligned = true;
  placed.residual_m = 0.04;
  placed.overlap_score = 0.99;
  placed.source = "correlation yaw 58.6 deg, peak 1";
  placed.restart_spread_voxels = 2.5;
  m.record.inputs = {reference, placed};
  return m;
}

class WebFixture : public ::testing::Test {
 protected:
  void SetUp() override {
    config_.listen = "127.0.0.1:0";
    config_.db_path = dir_.File("map.db");
    config_.shutdown_grace_s = 1.0;
  }
  void TearDown() override {
    web_.reset();
    server_.reset();
  }

  std::string web_address_ = "127.0.0.1";  // the web view's --http.address

  void Start() {
    auto server = service::MapServer::Start(config_);
    ASSERT_TRUE(server.ok()) << server.status().ToString();
    server_ = std::move(server).value();
    ASSERT_TRUE(server_->WaitUntilServing(std::chrono::seconds(30)));
    web::WebServerOptions options;
    options.auth.required = config_.auth_required;
    options.address = web_address_;
    const service::MapDirectory* maps = &server_->maps();
    options.list_maps = [maps] { return maps->Ids(); };
    options.find_map = [maps](const std::string& id) { return maps->FindCore(id); };
    auto web = web::WebServer::Start(server_->core(), options);
    ASSERT_TRUE(web.ok()) << web.status().ToString();
    web_ = std::move(web).value();
    stub_ = pb::MapService::NewStub(
        grpc::CreateChannel(server_->address(), grpc::InsecureChannelCredentials()));
  }

  httplib::Client Client() const {
    httplib::Client c("127.0.0.1", web_->port());
    c.set_read_timeout(30);
    return c;
  }

  // Streams `batches` (with `token` when not empty) and expects every one stored.
  void Ingest(const std::vector<pb::ObservationBatch>& batches, const std::string& token = "") {
    grpc::ClientContext ctx;
    if (!token.empty()) ctx.AddMetadata("authorization", "Bearer " + token);
    auto stream = stub_->Ingest(&ctx);
    for (const auto& b : batches) ASSERT_TRUE(stream->Write(b));
    stream->WritesDone();
    pb::IngestAck ack;
    int stored = 0;
    while (stream->Read(&ack)) stored += ack.result() == pb::IngestAck::STORED;
    ASSERT_TRUE(stream->Finish().ok());
    ASSERT_EQ(stored, static_cast<int>(batches.size()));
  }

  std::string MakeToken(service::Role role, const std::string& name,
                        const std::vector<std::string>& maps = {}) {
    std::string token;
    const Status s = server_->core()->ExecuteWrite([&](storage::WriteTransaction* txn) {
      service::NewToken t;
      t.name = name;
      t.role = role;
      t.created_by = "test";
      t.maps = maps;
      StatusOr<service::IssuedToken> issued = service::IssueToken(t, 1, txn);
      if (issued.ok()) token = issued->token;
      return issued.status();
    });
    EXPECT_TRUE(s.ok()) << s.ToString();
    return token;
  }

  // GET `path` as JSON; expects `status`.
  json GetJson(const std::string& path, int status = 200, const std::string& token = "") {
    httplib::Headers headers;
    if (!token.empty()) headers.emplace("Authorization", "Bearer " + token);
    httplib::Result r = Client().Get(path.c_str(), headers);
    EXPECT_TRUE(r) << path << ": " << httplib::to_string(r.error());
    if (!r) return json();
    EXPECT_EQ(r->status, status) << path << ": " << r->body;
    EXPECT_EQ(r->get_header_value("Content-Type"), "application/json") << path;
    return json::parse(r->body);
  }

  TempDir dir_;
  service::ServerConfig config_;
  std::unique_ptr<service::MapServer> server_;
  std::unique_ptr<web::WebServer> web_;
  std::unique_ptr<pb::MapService::Stub> stub_;
};

}  // namespace mapd::testing

#endif  // MAPD_TESTS_WEB_WEB_FIXTURE_H_
