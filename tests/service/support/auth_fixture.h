// A ServerFixture with identities: tokens made offline in the database file
// (as `mapd token create` does) or through the API, and call contexts that
// carry them.
#ifndef MAPD_TESTS_SERVICE_SUPPORT_AUTH_FIXTURE_H_
#define MAPD_TESTS_SERVICE_SUPPORT_AUTH_FIXTURE_H_

#include <memory>
#include <string>
#include <vector>

#include "common/clock.h"
#include "service/server_fixture.h"
#include "service/token.h"
#include "storage/sqlite/store.h"
#include "storage/store.h"

namespace mapd::testing {

class AuthFixture : public ServerFixture {
 protected:
  // An admin made offline ("root"), and one token per role made through the
  // API: reader "dashboard", robot "r1-key" of r1, operator "alice".
  void MakeTokens() {
    admin_ = OfflineToken(service::Role::kAdmin, "root");
    reader_ = ApiToken(admin_, pb::ROLE_READER, "dashboard");
    robot_ = ApiToken(admin_, pb::ROLE_ROBOT, "r1-key", "r1");
    operator_ = ApiToken(admin_, pb::ROLE_OPERATOR, "alice");
  }

  // A token written straight into the database (the server may run).
  std::string OfflineToken(service::Role role, const std::string& name,
                           const std::string& robot = "") {
    // With data_dir the tokens are in the default map's database.
    const std::string db =
        config_.data_dir.empty() ? config_.db_path : config_.data_dir + "/default.db";
    auto store = storage::SqliteStore::Open(db, storage::StoreOptions{});
    EXPECT_TRUE(store.ok()) << store.status().ToString();
    if (!store.ok()) return "";
    auto txn = (*store)->BeginWrite();
    EXPECT_TRUE(txn.ok());
    service::NewToken t{name, role, robot, "test", {}};
    auto issued = service::IssueToken(t, UnixNowNs(), txn->get());
    EXPECT_TRUE(issued.ok()) << issued.status().ToString();
    EXPECT_TRUE((*txn)->Commit().ok());
    return issued.ok() ? issued->token : "";
  }

  // CreateToken called with `caller`'s token; the new secret in *secret.
  grpc::Status CreateTokenAs(const std::string& caller, pb::Role role, const std::string& name,
                             const std::string& robot = "", std::string* secret = nullptr,
                             const std::vector<std::string>& maps = {}) {
    pb::CreateTokenRequest request;
    request.set_name(name);
    request.set_role(role);
    request.set_robot_id(robot);
    for (const std::string& map : maps) request.add_maps(map);
    pb::CreateTokenResponse response;
    auto ctx = As(caller);
    const grpc::Status s = stub_->CreateToken(ctx.get(), request, &response);
    if (secret != nullptr) *secret = response.token();
    return s;
  }

  // A token made through CreateToken with `admin`'s token.
  std::string ApiToken(const std::string& admin, pb::Role role, const std::string& name,
                       const std::string& robot = "") {
    std::string secret;
    const grpc::Status s = CreateTokenAs(admin, role, name, robot, &secret);
    EXPECT_TRUE(s.ok()) << s.error_message();
    return secret;
  }

  static std::unique_ptr<grpc::ClientContext> As(const std::string& token) {
    auto ctx = std::make_unique<grpc::ClientContext>();
    if (!token.empty()) ctx->AddMetadata("authorization", "Bearer " + token);
    return ctx;
  }

  grpc::Status StatsAs(const std::string& token) {
    auto ctx = As(token);
    pb::Stats stats;
    return stub_->GetStats(ctx.get(), {}, &stats);
  }

  // One Ingest stream with `token`: every ack, and the stream's status in *status.
  std::vector<pb::IngestAck> StreamAs(const std::string& token,
                                      const std::vector<pb::ObservationBatch>& batches,
                                      grpc::Status* status) {
    auto ctx = As(token);
    auto stream = stub_->Ingest(ctx.get());
    for (const auto& b : batches) {
      if (!stream->Write(b)) break;
    }
    stream->WritesDone();
    std::vector<pb::IngestAck> acks;
    pb::IngestAck ack;
    while (stream->Read(&ack)) acks.push_back(ack);
    *status = stream->Finish();
    return acks;
  }

  std::vector<pb::AuditEntry> Audit(const std::string& token) {
    auto ctx = As(token);
    pb::ListAuditRequest request;
    pb::ListAuditResponse response;
    const grpc::Status s = stub_->ListAudit(ctx.get(), request, &response);
    EXPECT_TRUE(s.ok()) << s.error_message();
    return {response.entries().begin(), response.entries().end()};
  }

  std::vector<pb::RobotInfo> Robots(const std::string& token) {
    auto ctx = As(token);
    pb::ListRobotsResponse response;
    EXPECT_TRUE(stub_->ListRobots(ctx.get(), {}, &response).ok());
    return {response.robots().begin(), response.robots().end()};
  }

  std::string admin_, reader_, robot_, operator_;  // MakeTokens
};

}  // namespace mapd::testing

#endif  // MAPD_TESTS_SERVICE_SUPPORT_AUTH_FIXTURE_H_
