// A Store on a fresh database file for each test, shared by the storage tests.
#ifndef MAPD_TESTS_STORAGE_SUPPORT_STORE_FIXTURE_H_
#define MAPD_TESTS_STORAGE_SUPPORT_STORE_FIXTURE_H_

#include <gtest/gtest.h>

#include <memory>
#include <string>
#include <utility>

#include "common/temp_dir.h"
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

class StoreFixture : public ::testing::Test {
 protected:
  void SetUp() override { Reopen(); }

  // Closes the store (if open) and opens the same file again.
  void Reopen() {
    store_.reset();
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

  // Runs `fn` in one write transaction and commits it when fn succeeds.
  template <typename Fn>
  Status Write(Fn fn) {
    auto txn = store_->BeginWrite();
    if (!txn.ok()) return txn.status();
    Status s = fn(txn->get());
    if (!s.ok()) return s;
    return (*txn)->Commit();
  }

  mapd::testing::TempDir dir_;
  std::unique_ptr<Store> store_;
};

}  // namespace mapd::storage::testing

#endif  // MAPD_TESTS_STORAGE_SUPPORT_STORE_FIXTURE_H_
