// Identities, roles and the audit log through the real server (docs/security.md).
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <fstream>

#include "client/robot/robot_client.h"
#include "common/health.h"
#include "common/temp_dir.h"
#include "service/support/auth_fixture.h"

namespace mapd::testing {
namespace {

using service::Role;
using ::testing::HasSubstr;

using AuthTest = AuthFixture;

TEST_F(AuthTest, LoopbackWithoutTokensIsOpenButCannotMintTokens) {
  EXPECT_TRUE(StatsAs("").ok());
  EXPECT_EQ(Stream(Walk("r1", 3)).size(), 3u);
  auto ctx = As("");
  pb::WhoAmIResponse me;
  ASSERT_TRUE(stub_->WhoAmI(ctx.get(), {}, &me).ok());
  EXPECT_TRUE(me.anonymous());
  // The open mode never hands out the keys: the first token needs file access.
  pb::CreateTokenRequest request;
  request.set_name("sneaky");
  request.set_role(pb::ROLE_ADMIN);
  pb::CreateTokenResponse response;
  auto ctx2 = As("");
  const grpc::Status s = stub_->CreateToken(ctx2.get(), request, &response);
  EXPECT_EQ(s.error_code(), grpc::StatusCode::PERMISSION_DENIED);
  EXPECT_THAT(s.error_message(), HasSubstr("mapd token create"));
}

TEST_F(AuthTest, OnceATokenExistsEveryCallNeedsOneButHealthStaysOpen) {
  admin_ = OfflineToken(Role::kAdmin, "root");
  const grpc::Status s = StatsAs("");
  EXPECT_EQ(s.error_code(), grpc::StatusCode::UNAUTHENTICATED);
  EXPECT_THAT(s.error_message(), HasSubstr("Bearer"));
  grpc::Status stream_status;
  EXPECT_TRUE(StreamAs("", Walk("r1", 2), &stream_status).empty());
  EXPECT_EQ(stream_status.error_code(), grpc::StatusCode::UNAUTHENTICATED);
  EXPECT_EQ(CheckHealth(server_->address()), Health::kServing);
  auto ctx = As(admin_);
  pb::Stats stats;
  ASSERT_TRUE(stub_->GetStats(ctx.get(), {}, &stats).ok());
  EXPECT_EQ(stats.batches(), 0u) << "nothing of the refused stream was stored";
}

TEST_F(AuthTest, AuthRequiredWithoutAnyTokenRefusesEverything) {
  config_.auth_required = true;
  Restart();
  EXPECT_EQ(StatsAs("").error_code(), grpc::StatusCode::UNAUTHENTICATED);
}

TEST_F(AuthTest, MalformedUnknownAndForgedTokensAreUnauthenticated) {
  MakeTokens();
  EXPECT_EQ(StatsAs("garbage").error_code(), grpc::StatusCode::UNAUTHENTICATED);
  EXPECT_EQ(StatsAs("mapd_999_abc").error_code(), grpc::StatusCode::UNAUTHENTICATED);
  std::string forged = robot_;
  forged.back() = forged.back() == 'A' ? 'B' : 'A';  // right id, wrong secret
  EXPECT_EQ(StatsAs(forged).error_code(), grpc::StatusCode::UNAUTHENTICATED);
  auto ctx = std::make_unique<grpc::ClientContext>();
  ctx->AddMetadata("authorization", "Basic " + robot_);
  pb::Stats stats;
  EXPECT_EQ(stub_->GetStats(ctx.get(), {}, &stats).error_code(), grpc::StatusCode::UNAUTHENTICATED);
}

TEST_F(AuthTest, EachRoleGetsExactlyItsPermissions) {
  MakeTokens();
  for (const std::string* t : {&reader_, &robot_, &operator_, &admin_})
    EXPECT_TRUE(StatsAs(*t).ok());
  // Trails are a read of the map: every role, and not without a token.
  auto trails = [&](const std::string& t) {
    auto ctx = As(t);
    auto reader = stub_->GetTrails(ctx.get(), {});
    pb::SessionTrail trail;
    while (reader->Read(&trail)) {
    }
    return reader->Finish().error_code();
  };
  for (const std::string* t : {&reader_, &robot_, &operator_, &admin_})
    EXPECT_EQ(trails(*t), grpc::StatusCode::OK);
  EXPECT_EQ(trails(""), grpc::StatusCode::UNAUTHENTICATED);

  auto list_tokens = [&](const std::string& t) {
    auto ctx = As(t);
    pb::ListTokensResponse r;
    return stub_->ListTokens(ctx.get(), {}, &r);
  };
  EXPECT_TRUE(list_tokens(admin_).ok());
  for (const std::string* t : {&reader_, &robot_, &operator_}) {
    const grpc::Status s = list_tokens(*t);
    EXPECT_EQ(s.error_code(), grpc::StatusCode::PERMISSION_DENIED);
    EXPECT_THAT(s.error_message(), HasSubstr("manage_tokens"));
  }
  const grpc::Status op = list_tokens(operator_);
  EXPECT_THAT(op.error_message(), HasSubstr("role operator"));

  auto audit = [&](const std::string& t) {
    auto ctx = As(t);
    pb::ListAuditResponse r;
    return stub_->ListAudit(ctx.get(), {}, &r).error_code();
  };
  EXPECT_EQ(audit(reader_), grpc::StatusCode::PERMISSION_DENIED);
  EXPECT_EQ(audit(robot_), grpc::StatusCode::PERMISSION_DENIED);
  EXPECT_EQ(audit(operator_), grpc::StatusCode::OK);
  EXPECT_EQ(audit(admin_), grpc::StatusCode::OK);

  // Merging: operators and admins get past the door (and then INVALID_ARGUMENT).
  auto merge = [&](const std::string& t) {
    auto ctx = As(t);
    pb::MergeSubmapsRequest request;
    request.add_submap_ids(1);
    auto reader = stub_->MergeSubmaps(ctx.get(), request);
    pb::MergeProgress p;
    while (reader->Read(&p)) {
    }
    return reader->Finish();
  };
  const grpc::Status reader_merge = merge(reader_);
  EXPECT_EQ(reader_merge.error_code(), grpc::StatusCode::PERMISSION_DENIED);
  EXPECT_THAT(reader_merge.error_message(), HasSubstr("role reader"));
  EXPECT_THAT(reader_merge.error_message(), HasSubstr("merge"));
  EXPECT_EQ(merge(robot_).error_code(), grpc::StatusCode::PERMISSION_DENIED);
  EXPECT_EQ(merge(operator_).error_code(), grpc::StatusCode::INVALID_ARGUMENT);

  // A reader never writes.
  grpc::Status s;
  EXPECT_TRUE(StreamAs(reader_, Walk("r1", 2), &s).empty());
  EXPECT_EQ(s.error_code(), grpc::StatusCode::PERMISSION_DENIED);
  EXPECT_THAT(s.error_message(), HasSubstr("write"));
  auto del = [&](const std::string& t) {
    auto ctx = As(t);
    pb::DeleteSubmapRequest request;
    request.set_id(42);
    pb::DeleteSubmapResponse r;
    return stub_->DeleteSubmap(ctx.get(), request, &r).error_code();
  };
  EXPECT_EQ(del(operator_), grpc::StatusCode::NOT_FOUND);
}

TEST_F(AuthTest, RobotWritesOnlyItsOwnRobotAndNothingElseIsStored) {
  MakeTokens();
  std::vector<pb::ObservationBatch> batches = Walk("r1", 3);
  for (pb::ObservationBatch& b : Walk("r2", 2, 100)) batches.push_back(b);
  grpc::Status s;
  const std::vector<pb::IngestAck> acks = StreamAs(robot_, batches, &s);
  ASSERT_TRUE(s.ok()) << s.error_message();
  ASSERT_EQ(acks.size(), 5u);
  int stored = 0, denied = 0;
  for (const pb::IngestAck& a : acks) {
    if (a.result() == pb::IngestAck::STORED) ++stored;
    if (a.result() == pb::IngestAck::REJECTED && a.code() == grpc::StatusCode::PERMISSION_DENIED) {
      ++denied;
      EXPECT_THAT(a.message(), HasSubstr("robot 'r2'"));
    }
  }
  EXPECT_EQ(stored, 3);
  EXPECT_EQ(denied, 2);
  const std::vector<pb::RobotInfo> robots = Robots(operator_);
  ASSERT_EQ(robots.size(), 1u);
  EXPECT_EQ(robots[0].robot_id(), "r1");
  EXPECT_EQ(robots[0].batches(), 3u);

  // The first denial of the stream is audited, with who and why.
  bool audited = false;
  for (const pb::AuditEntry& e : Audit(operator_)) {
    if (e.action() == "Ingest") {
      audited = true;
      EXPECT_EQ(e.who(), "r1-key");
      EXPECT_EQ(e.role(), "robot");
      EXPECT_THAT(e.target(), HasSubstr("robot r2"));
      EXPECT_THAT(e.result(), HasSubstr("denied"));
    }
  }
  EXPECT_TRUE(audited);
}

TEST_F(AuthTest, RobotSeesOnlyItsOwnSubmapsAndCannotDeleteOthers) {
  MakeTokens();
  auto list = [&](const std::string& token, const std::string& robot) {
    auto ctx = As(token);
    pb::ListSubmapsRequest request;
    request.set_robot_id(robot);
    pb::ListSubmapsResponse r;
    return stub_->ListSubmaps(ctx.get(), request, &r).error_code();
  };
  EXPECT_EQ(list(robot_, ""), grpc::StatusCode::OK);  // scoped to r1
  EXPECT_EQ(list(robot_, "r1"), grpc::StatusCode::OK);
  EXPECT_EQ(list(robot_, "r2"), grpc::StatusCode::PERMISSION_DENIED);
  EXPECT_EQ(list(reader_, "r2"), grpc::StatusCode::OK);
}

TEST_F(AuthTest, UploadForAnotherRobotIsDeniedBeforeAnyByteIsStored) {
  MakeTokens();
  auto ctx = As(robot_);
  pb::SubmapInfo info;
  auto writer = stub_->UploadSubmap(ctx.get(), &info);
  pb::UploadSubmapRequest header;
  header.mutable_header()->set_robot_id("r2");
  header.mutable_header()->set_name("room");
  header.mutable_header()->set_format(pb::SUBMAP_FORMAT_OCTOMAP_BT);
  writer->Write(header);
  pb::UploadSubmapRequest chunk;
  chunk.set_chunk("# Octomap OcTree binary file\n");
  writer->Write(chunk);
  writer->WritesDone();
  const grpc::Status s = writer->Finish();
  EXPECT_EQ(s.error_code(), grpc::StatusCode::PERMISSION_DENIED) << s.error_message();
  EXPECT_THAT(s.error_message(), HasSubstr("robot 'r2'"));
  bool audited = false;
  for (const pb::AuditEntry& e : Audit(admin_)) {
    audited = audited || (e.action() == "UploadSubmap" && e.result().rfind("denied", 0) == 0);
  }
  EXPECT_TRUE(audited);
  auto list_ctx = As(admin_);
  pb::ListSubmapsResponse submaps;
  ASSERT_TRUE(stub_->ListSubmaps(list_ctx.get(), {}, &submaps).ok());
  EXPECT_EQ(submaps.submaps_size(), 0);
}

TEST_F(AuthTest, RevokedTokenIsRefusedAndTheRevocationIsAudited) {
  MakeTokens();
  ASSERT_TRUE(StatsAs(robot_).ok());
  auto ctx = As(admin_);
  pb::ListTokensResponse tokens;
  ASSERT_TRUE(stub_->ListTokens(ctx.get(), {}, &tokens).ok());
  uint64_t robot_id = 0;
  for (const pb::TokenInfo& t : tokens.tokens()) {
    if (t.name() == "r1-key") robot_id = t.id();
  }
  ASSERT_NE(robot_id, 0u);
  pb::RevokeTokenRequest revoke;
  revoke.set_id(robot_id);
  pb::RevokeTokenResponse revoked;
  auto ctx2 = As(admin_);
  ASSERT_TRUE(stub_->RevokeToken(ctx2.get(), revoke, &revoked).ok());
  EXPECT_NE(revoked.info().revoked_ns(), 0);

  const grpc::Status s = StatsAs(robot_);
  EXPECT_EQ(s.error_code(), grpc::StatusCode::UNAUTHENTICATED);
  EXPECT_THAT(s.error_message(), HasSubstr("revoked"));
  grpc::Status stream_status;
  EXPECT_TRUE(StreamAs(robot_, Walk("r1", 2), &stream_status).empty());
  EXPECT_EQ(stream_status.error_code(), grpc::StatusCode::UNAUTHENTICATED);
  EXPECT_EQ(Robots(admin_).size(), 0u);

  const std::vector<pb::AuditEntry> audit = Audit(admin_);
  ASSERT_FALSE(audit.empty());
  EXPECT_EQ(audit[0].action(), "RevokeToken");  // newest first
  EXPECT_EQ(audit[0].who(), "root");
  EXPECT_EQ(audit[0].credential(), "token");
  EXPECT_FALSE(audit[0].peer().empty());
  EXPECT_THAT(audit[0].target(), HasSubstr("r1-key"));
  int created = 0;
  for (const pb::AuditEntry& e : audit) created += e.action() == "CreateToken";
  EXPECT_EQ(created, 3);
}

// The database is the trust root: its path is for operators (issue 43).
TEST_F(AuthTest, OnlyOperatorsAndAdminsSeeTheDatabasePath) {
  MakeTokens();
  for (const auto& [token, shown] : std::vector<std::pair<std::string, bool>>{
           {reader_, false}, {robot_, false}, {operator_, true}, {admin_, true}}) {
    auto ctx = As(token);
    pb::Stats stats;
    ASSERT_TRUE(stub_->GetStats(ctx.get(), {}, &stats).ok());
    EXPECT_EQ(stats.db_path(), shown ? config_.db_path : "");
    EXPECT_GT(stats.db_size_bytes(), 0u);
  }
}

TEST_F(AuthTest, SecretsNeverReachTheDatabaseFile) {
  MakeTokens();
  server_.reset();  // checkpoints: everything is in the main file (and any WAL left)
  const std::string db = ReadFileBytes(config_.db_path) + ReadFileBytes(config_.db_path + "-wal");
  ASSERT_FALSE(db.empty());
  for (const std::string* t : {&admin_, &reader_, &robot_, &operator_}) {
    const std::string secret = t->substr(t->find('_', 5) + 1);  // mapd_<id>_<secret>
    ASSERT_GE(secret.size(), 40u);
    EXPECT_EQ(db.find(secret), std::string::npos) << "a secret is stored in clear";
    EXPECT_NE(db.find(service::Sha256(secret)), std::string::npos) << "its hash should be";
  }
  StartServer();
}

TEST_F(AuthTest, RobotClientStreamsWithItsTokenAndGivesUpAtOnceWithoutOne) {
  MakeTokens();
  robot::RobotClientOptions options;
  options.token = robot_;
  robot::RobotClient ok(channel_, options);
  for (const pb::ObservationBatch& b : Walk("r1", 4)) ok.Send(b);
  EXPECT_TRUE(ok.Finish(std::chrono::seconds(30)).ok());
  EXPECT_EQ(ok.counts().stored, 4u);

  options.token = "mapd_1_wrong";
  options.give_up_after = std::chrono::hours(1);  // a refusal must not be retried until then
  robot::RobotClient refused(channel_, options);
  refused.Send(Walk("r1", 1, 10)[0]);
  EXPECT_EQ(refused.Finish(std::chrono::hours(1)).error_code(), grpc::StatusCode::UNAUTHENTICATED);
}

}  // namespace
}  // namespace mapd::testing
