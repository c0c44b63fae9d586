// What reaches the audit log, through the real server (docs/security.md,
// "The audit log"): only well-formed ids, one line per row.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <chrono>
#include <map>

#include "service/support/auth_fixture.h"

namespace mapd::testing {
namespace {

using ::testing::HasSubstr;
using ::testing::Not;

using AuditTest = AuthFixture;

// A field an attacker could use to forge a row or drive a terminal.
bool HasControlCharacter(const std::string& s) {
  for (unsigned char c : s) {
    if (c < 0x20 || c == 0x7F) return true;
  }
  return false;
}

void ExpectOneLineRows(const std::vector<pb::AuditEntry>& audit) {
  for (const pb::AuditEntry& e : audit) {
    for (const std::string* field : {&e.who(), &e.role(), &e.action(), &e.target(), &e.result()})
      EXPECT_FALSE(HasControlCharacter(*field)) << "audit row " << e.id() << ": " << *field;
  }
}

TEST_F(AuditTest, ARobotIdWithANewlineIsRefusedBeforeItIsRecorded) {
  MakeTokens();
  // Another robot's id, then a line that looks like an admin's audit row.
  const std::string forged = "r2\n2026-12-04T10:00:00Z root admin RevokeToken token 1 ok\x1b[0m";
  std::vector<pb::ObservationBatch> batches = Walk("r1", 1);
  batches[0].set_robot_id(forged);
  grpc::Status status;
  const std::vector<pb::IngestAck> acks = StreamAs(robot_, batches, &status);
  ASSERT_TRUE(status.ok()) << status.error_message();
  ASSERT_EQ(acks.size(), 1u);
  EXPECT_EQ(acks[0].result(), pb::IngestAck::REJECTED);
  EXPECT_EQ(acks[0].code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_THAT(acks[0].message(), HasSubstr("robot_id 'r2\\n2026"));
  EXPECT_FALSE(HasControlCharacter(acks[0].message())) << acks[0].message();

  const std::vector<pb::AuditEntry> audit = Audit(operator_);
  ExpectOneLineRows(audit);
  for (const pb::AuditEntry& e : audit) {
    EXPECT_NE(e.action(), "Ingest") << "an invalid batch is refused, not audited: " << e.target();
  }
}

TEST_F(AuditTest, ADeniedBatchIsAuditedWithItsValidatedIds) {
  MakeTokens();
  grpc::Status status;
  const std::vector<pb::IngestAck> acks = StreamAs(robot_, Walk("r2", 1), &status);
  ASSERT_EQ(acks.size(), 1u);
  EXPECT_EQ(acks[0].code(), grpc::StatusCode::PERMISSION_DENIED);
  bool audited = false;
  for (const pb::AuditEntry& e : Audit(operator_)) {
    if (e.action() != "Ingest") continue;
    audited = true;
    EXPECT_THAT(e.target(), HasSubstr("robot r2 session"));
  }
  EXPECT_TRUE(audited);
}

TEST_F(AuditTest, ATokenNameWithControlCharactersIsRefused) {
  MakeTokens();
  const grpc::Status s = CreateTokenAs(admin_, pb::ROLE_READER, "ci\nfake row");
  EXPECT_EQ(s.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_THAT(s.error_message(), HasSubstr("name must be"));
  ExpectOneLineRows(Audit(admin_));
  for (const pb::AuditEntry& e : Audit(admin_)) EXPECT_THAT(e.target(), Not(HasSubstr("fake")));
}

TEST_F(AuditTest, DeniedCallsNameWhatTheyWouldHaveActedOn) {
  MakeTokens();
  auto ctx = As(reader_);
  pb::MergeSubmapsRequest merge;
  merge.add_submap_ids(4);
  merge.add_submap_ids(9);
  pb::MergeProgress progress;
  auto stream = stub_->MergeSubmaps(ctx.get(), merge);
  while (stream->Read(&progress)) {
  }
  EXPECT_EQ(stream->Finish().error_code(), grpc::StatusCode::PERMISSION_DENIED);
  for (const bool approve : {true, false}) {
    auto c = As(reader_);
    pb::MergeRecord record;
    grpc::Status s;
    if (approve) {
      pb::ApproveMergeRequest r;
      r.set_id(7);
      s = stub_->ApproveMerge(c.get(), r, &record);
    } else {
      pb::RejectMergeRequest r;
      r.set_id(8);
      r.set_reason("no");
      s = stub_->RejectMerge(c.get(), r, &record);
    }
    EXPECT_EQ(s.error_code(), grpc::StatusCode::PERMISSION_DENIED);
  }
  EXPECT_EQ(CreateTokenAs(operator_, pb::ROLE_ADMIN, "mint").error_code(),
            grpc::StatusCode::PERMISSION_DENIED);

  std::map<std::string, std::string> target_of;
  for (const pb::AuditEntry& e : Audit(admin_)) {
    if (e.result().rfind("denied", 0) != 0) continue;
    target_of[e.action()] = e.target();
    // Who it was is told by how (the credential) and from where.
    EXPECT_EQ(e.credential(), "token") << e.action();
    EXPECT_THAT(e.peer(), ::testing::MatchesRegex("ipv[46]:.*:[0-9]+")) << e.action();
  }
  EXPECT_EQ(target_of["MergeSubmaps"], "submaps 4,9");
  EXPECT_EQ(target_of["ApproveMerge"], "merge 7");
  EXPECT_EQ(target_of["RejectMerge"], "merge 8");
  EXPECT_EQ(target_of["CreateToken"], "token 'mint' ROLE_ADMIN");
}

// A reader token once added 500 rows in 0.16 s (issue 43).
TEST_F(AuditTest, AFloodOfDenialsIsCountedNotRecordedOneByOne) {
  MakeTokens();
  const size_t before = Audit(admin_).size();
  const auto start = std::chrono::steady_clock::now();
  for (int i = 0; i < 500; ++i) {
    ASSERT_EQ(CreateTokenAs(reader_, pb::ROLE_ADMIN, "x").error_code(),
              grpc::StatusCode::PERMISSION_DENIED);
  }
  // The summary comes when the reader may write a row again (6 s at 10 a
  // minute) or at shutdown: stop the server to read it at once. A slow host
  // (sanitizers) gets one more row per 6 s the flood took.
  const std::string op = operator_;
  Restart();
  const double took_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const size_t slack = 2 + static_cast<size_t>(took_s / 6.0);
  const std::vector<pb::AuditEntry> audit = Audit(op);
  int denial_rows = 0;
  std::string summary;
  for (const pb::AuditEntry& e : audit) {
    if (e.who() != "dashboard") continue;
    ++denial_rows;
    if (e.result().find("more denials") != std::string::npos) summary = e.result();
  }
  EXPECT_LE(static_cast<size_t>(denial_rows), 10 + slack);  // the burst, then summaries
  EXPECT_LE(audit.size(), before + 10 + slack);
  EXPECT_THAT(summary, HasSubstr("more denials of CreateToken by dashboard"));
  // An allowed privileged action is recorded whatever the denials did.
  ApiToken(admin_, pb::ROLE_READER, "after-the-flood");
  bool created = false;
  for (const pb::AuditEntry& e : Audit(op)) {
    created = created || (e.action() == "CreateToken" && e.result() == "ok" &&
                          e.target().find("after-the-flood") != std::string::npos);
  }
  EXPECT_TRUE(created);
}

}  // namespace
}  // namespace mapd::testing
