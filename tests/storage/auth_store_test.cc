// Tokens and the audit log in the SQLite store (storage/auth_store.cc).
#include <gtest/gtest.h>

#include "storage/store.h"
#include "storage/support/store_fixture.h"

namespace mapd::storage {
namespace {

using AuthStoreTest = testing::StoreFixture;

TEST_F(AuthStoreTest, AuditFieldsAreStoredAsOneLineOfVisibleText) {
  AuditEntry e;
  e.time_ns = 1;
  e.who = "r1-key";
  e.role = "robot";
  e.action = "Ingest";
  e.target = "robot r2\n2026-12-04T10:00:00Z root admin RevokeToken ok";
  e.result = "denied: \x1b[2J\r\t\x7f \xc2\x9b tail";
  e.peer = "ipv4:127.0.0.1:4242";
  e.credential = "token";
  auto txn = store_->BeginWrite();
  ASSERT_TRUE(txn.ok());
  ASSERT_TRUE((*txn)->AppendAudit(e).ok());
  ASSERT_TRUE((*txn)->Commit().ok());

  StatusOr<std::vector<AuditEntry>> rows = store_->ListAudit(10);
  ASSERT_TRUE(rows.ok()) << rows.status().ToString();
  ASSERT_EQ(rows->size(), 1u);
  EXPECT_EQ((*rows)[0].who, "r1-key");
  EXPECT_EQ((*rows)[0].target, "robot r2\\n2026-12-04T10:00:00Z root admin RevokeToken ok");
  EXPECT_EQ((*rows)[0].result, "denied: \\x1b[2J\\r\\t\\x7f \\u009b tail");
  EXPECT_EQ((*rows)[0].peer, "ipv4:127.0.0.1:4242");
  EXPECT_EQ((*rows)[0].credential, "token");
}

TEST_F(AuthStoreTest, TrimmingKeepsTheNewestDenialsAndEveryOtherRow) {
  auto txn = store_->BeginWrite();
  ASSERT_TRUE(txn.ok());
  for (int i = 0; i < 30; ++i) {
    AuditEntry e;
    e.time_ns = i;
    e.who = "w";
    e.role = "reader";
    e.action = "A";
    e.target = std::to_string(i);
    e.result = i % 3 == 0 ? "ok" : "denied: no";
    ASSERT_TRUE((*txn)->AppendAudit(e).ok());
  }
  StatusOr<int64_t> deleted = (*txn)->TrimDeniedAudit(5);
  ASSERT_TRUE(deleted.ok()) << deleted.status().ToString();
  EXPECT_EQ(*deleted, 20 - 5);
  ASSERT_TRUE((*txn)->Commit().ok());
  StatusOr<std::vector<AuditEntry>> rows = store_->ListAudit(100);
  ASSERT_TRUE(rows.ok());
  int ok = 0, denied = 0;
  for (const AuditEntry& e : *rows) {
    if (e.result == "ok") ++ok;
    if (e.result != "ok") {
      ++denied;
      EXPECT_GE(std::stoi(e.target), 22) << "the newest denials are kept";
    }
  }
  EXPECT_EQ(ok, 10);
  EXPECT_EQ(denied, 5);
}

}  // namespace
}  // namespace mapd::storage
