// Tokens and the audit log in the SQLite store (storage/auth_store.cc).
#include <gtest/gtest.h>

#include "storage/store.h"
#include "storage/support/store_fixture.h"

namespace mapd::storage {
namespace {

using AuthStoreTest = testing::StoreFixture;

using AuthStoreConformanceTest = testing::OnEveryBackend<AuthStoreTest>;

TEST_P(AuthStoreConformanceTest, AuditFieldsAreStoredAsOneLineOfVisibleText) {
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

// A token's map scope is stored; tokens of a database from before scopes
// (schema 11) read as unscoped after the migration.
TEST_F(AuthStoreTest, TokenScopesAreStoredAndOlderTokensActOnEveryMap) {
  TokenRecord scoped, old;
  scoped.name = "site-7-robot";
  scoped.role = "robot";
  scoped.robot_id = "r7";
  scoped.secret_sha256 = std::string(32, 'a');
  scoped.maps = "site-7,site-8";
  old.name = "old";
  old.role = "reader";
  old.secret_sha256 = std::string(32, 'b');
  ASSERT_TRUE(Write([&](WriteTransaction* txn) {
                MAPD_RETURN_IF_ERROR(txn->InsertToken(scoped).status());
                return txn->InsertToken(old).status();
              }).ok());
  auto tokens = store_->ListTokens();
  ASSERT_TRUE(tokens.ok());
  ASSERT_EQ(tokens->size(), 2u);
  EXPECT_EQ((*tokens)[0].maps, "site-7,site-8");
  EXPECT_EQ((*tokens)[1].maps, "");

  DowngradeAndReopen(
      "ALTER TABLE tokens DROP COLUMN maps; DELETE FROM schema_version WHERE version >= 12");
  tokens = store_->ListTokens();
  ASSERT_TRUE(tokens.ok()) << tokens.status().ToString();
  ASSERT_EQ(tokens->size(), 2u);
  EXPECT_EQ((*tokens)[0].maps, "");  // the scope went with the downgrade: every map
  EXPECT_EQ((*tokens)[0].robot_id, "r7");
}

TEST_P(AuthStoreConformanceTest, TrimmingKeepsTheNewestDenialsAndEveryOtherRow) {
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

MAPD_ON_EVERY_BACKEND(AuthStoreConformanceTest);

}  // namespace
}  // namespace mapd::storage
