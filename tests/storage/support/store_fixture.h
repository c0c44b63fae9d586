// A Store on a fresh database file for each test, shared by the storage tests.
#ifndef MAPD_TESTS_STORAGE_SUPPORT_STORE_FIXTURE_H_
#define MAPD_TESTS_STORAGE_SUPPORT_STORE_FIXTURE_H_

#include <gtest/gtest.h>

#include <memory>
#include <string>
#include <utility>

#include "common/postgres.h"
#include "common/temp_dir.h"
#include "storage/postgres/store.h"
#include "storage/sqlite/sqlite.h"
#include "storage/sqlite/store.h"
#include "storage/store.h"

namespace mapd::storage::testing {

// SQL that turns schema 12 back into 11 (tokens not scoped to maps), 11 into
// 10 (no global map tables), schema 10's audit log back into schema 9's, then
// schema 9's snapshot tables back into schema 8's (the downgrades below schema
// 9 start with it).
constexpr const char* kUndoSnapshotParts =
    "ALTER TABLE tokens DROP COLUMN maps; "
    "DROP TABLE global_map; "
    "DROP TABLE submap_placements; "
    "ALTER TABLE audit_log DROP COLUMN peer; "
    "ALTER TABLE audit_log DROP COLUMN credential; "
    "DROP TABLE fusion_snapshot_parts; "
    "ALTER TABLE fusion_snapshots DROP COLUMN parts; "
    "ALTER TABLE fusion_snapshots DROP COLUMN parts_key; "
    "ALTER TABLE fusion_snapshots DROP COLUMN state_bytes; ";

// A Store on a fresh SQLite file, or (backend_ "postgresql") on a fresh
// database of the test's throw-away PostgreSQL cluster (skipped without one).
class StoreFixture : public ::testing::Test {
 protected:
  void SetUp() override {
    if (backend_ == "postgresql") {
      mapd::testing::PostgresCluster* cluster = mapd::testing::PostgresCluster::Shared();
      if (cluster == nullptr) GTEST_SKIP() << "no PostgreSQL (install postgresql-15)";
      conninfo_ = cluster->NewDatabase();
    }
    Reopen();
  }

  // Closes the store (if open) and opens the same file (database) again.
  void Reopen() {
    store_.reset();
    if (backend_ == "postgresql") {
      auto opened = PgStore::Open(conninfo_, "default", StoreOptions{});
      ASSERT_TRUE(opened.ok()) << opened.status().ToString();
      store_ = std::move(opened).value();
      return;
    }
    auto opened = SqliteStore::Open(dir_.File("map.db"), StoreOptions{});
    ASSERT_TRUE(opened.ok()) << opened.status().ToString();
    store_ = std::move(opened).value();
  }

  // Closes the store, runs `sql` on its file (to give it an older schema's
  // shape) and opens it again (which migrates it).
  void DowngradeAndReopen(const std::string& sql) {
    store_.reset();
    {
      auto db = OpenDatabase(dir_.File("map.db"), false);
      ASSERT_TRUE(db.ok());
      ASSERT_TRUE(Exec(db->get(), sql).ok()) << sql;
    }
    Reopen();
  }

  // The rows of `table` (the whole database's, under either backend).
  int64_t CountRows(const std::string& table) {
    const std::string sql = "SELECT count(*) FROM " + table;
    if (backend_ == "postgresql") {
      StatusOr<PgConnection> conn = PgConnection::Connect(conninfo_);
      EXPECT_TRUE(conn.ok()) << conn.status().ToString();
      if (!conn.ok()) return -1;
      StatusOr<PgResult> r = conn->Query(sql);
      EXPECT_TRUE(r.ok()) << r.status().ToString();
      return r.ok() ? r->Int(0, 0) : -1;
    }
    auto db = OpenDatabase(dir_.File("map.db"), true);
    EXPECT_TRUE(db.ok());
    if (!db.ok()) return -1;
    auto q = Statement::Prepare(db->get(), sql);
    EXPECT_TRUE(q.ok());
    return q.ok() && *q->Step() ? q->ColumnInt(0) : -1;
  }

  // Runs `fn` in one write transaction and commits it when fn succeeds.
  template <typename Fn>
  Status Write(Fn fn) {
    auto txn = store_->BeginWrite();
    if (!txn.ok()) return txn.status();
    Status s = fn(txn->get());
    if (!s.ok()) return s;
    return (*txn)->Commit();
  }

  std::string backend_ = "sqlite";
  std::string conninfo_;  // postgresql
  mapd::testing::TempDir dir_;
  std::unique_ptr<Store> store_;
};

// `Fixture`'s tests on every backend: the storage conformance suite.
//   using SubmapConformanceTest = OnEveryBackend<SubmapStoreTest>;
//   TEST_P(SubmapConformanceTest, ...) { ... }
//   MAPD_ON_EVERY_BACKEND(SubmapConformanceTest);
template <typename Fixture>
class OnEveryBackend : public Fixture, public ::testing::WithParamInterface<std::string> {
 protected:
  void SetUp() override {
    this->backend_ = this->GetParam();
    Fixture::SetUp();
  }
};

#define MAPD_ON_EVERY_BACKEND(Suite)                                                   \
  INSTANTIATE_TEST_SUITE_P(Backends, Suite, ::testing::Values("sqlite", "postgresql"), \
                           [](const ::testing::TestParamInfo<std::string>& p) { return p.param; })

}  // namespace mapd::storage::testing

#endif  // MAPD_TESTS_STORAGE_SUPPORT_STORE_FIXTURE_H_
