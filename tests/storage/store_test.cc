// The SQLite store: idempotent batches, frame kinds, transactions, reopening,
// the database stamp (newer mapd, foreign files) and the size cap.
#include "storage/sqlite/store.h"

#include <gtest/gtest.h>

#include "storage/sqlite/schema.h"
#include "storage/store.h"
#include "storage/support/store_fixture.h"

namespace mapd::storage {
namespace {

class StoreTest : public testing::StoreFixture {
 protected:
  NewObservation Batch(const std::string& robot, const std::string& session, uint64_t seq,
                       FrameKind kind = FrameKind::kMap) {
    NewObservation o;
    o.robot = robot;
    o.session = session;
    o.seq = seq;
    o.stamp_ns = 1000 + static_cast<int64_t>(seq);
    o.received_ns = 2000 + static_cast<int64_t>(seq);
    o.frame_kind = kind;
    o.features = &features_;
    return o;
  }

  StatusOr<InsertResult> InsertOne(const NewObservation& o) {
    auto txn = store_->BeginWrite();
    if (!txn.ok()) return txn.status();
    StatusOr<InsertResult> r = (*txn)->InsertObservation(o);
    if (!r.ok()) return r;
    Status c = (*txn)->Commit();
    if (!c.ok()) return c;
    return r;
  }

  geometry::SensorObservation features_ = [] {
    geometry::SensorObservation f;
    f.T_frame_sensor.translation = {1, 2, 0};
    f.lines.push_back({{0, 0, 0}, {3, 0, 0}});
    f.lines.push_back({{0, 1, 0}, {3, 1, 0}});
    return f;
  }();
};

using StoreConformanceTest = testing::OnEveryBackend<StoreTest>;

TEST_P(StoreConformanceTest, StoresABatchOnceAndReportsTheDuplicate) {
  auto first = InsertOne(Batch("r1", "s1", 1));
  ASSERT_TRUE(first.ok()) << first.status().ToString();
  EXPECT_TRUE(first->stored);
  auto again = InsertOne(Batch("r1", "s1", 1));
  ASSERT_TRUE(again.ok());
  EXPECT_FALSE(again->stored);
  EXPECT_EQ(again->observation_id, first->observation_id);

  auto counts = store_->Counts();
  ASSERT_TRUE(counts.ok());
  EXPECT_EQ(counts->observations, 1u);
  EXPECT_EQ(counts->raw_features, 2u);
}

TEST_P(StoreConformanceTest, SameSeqInAnotherSessionOrRobotIsNew) {
  auto first = InsertOne(Batch("r1", "s1", 1));
  ASSERT_TRUE(first.ok()) << first.status().ToString();
  EXPECT_TRUE(first->stored);
  auto other_session = InsertOne(Batch("r1", "s2", 1));
  auto other_robot = InsertOne(Batch("r2", "s1", 1));
  ASSERT_TRUE(other_session.ok() && other_robot.ok());
  EXPECT_TRUE(other_session->stored);
  EXPECT_TRUE(other_robot->stored);
  // Three rows, not one row found three times.
  EXPECT_NE(other_session->observation_id, first->observation_id);
  EXPECT_NE(other_robot->observation_id, first->observation_id);
  EXPECT_NE(other_robot->observation_id, other_session->observation_id);
  EXPECT_EQ(store_->Counts()->observations, 3u);
  auto robots = store_->ListRobots();
  ASSERT_TRUE(robots.ok());
  ASSERT_EQ(robots->size(), 2u);
  EXPECT_EQ((*robots)[0].name, "r1");
  EXPECT_EQ((*robots)[0].batches, 2u);
  EXPECT_EQ((*robots)[0].sessions, 2u);
  EXPECT_EQ((*robots)[1].name, "r2");
  EXPECT_EQ((*robots)[1].batches, 1u);
  EXPECT_EQ((*robots)[1].sessions, 1u);
}

TEST_P(StoreConformanceTest, RefusesAFrameKindThatDisagreesWithTheSession) {
  ASSERT_TRUE(InsertOne(Batch("r1", "s1", 1, FrameKind::kMap)).ok());
  auto bad = InsertOne(Batch("r1", "s1", 2, FrameKind::kLocal));
  EXPECT_EQ(bad.status().code(), StatusCode::kInvalidArgument);
  EXPECT_NE(bad.status().message().find("session_frame"), std::string::npos);
}

TEST_P(StoreConformanceTest, UncommittedTransactionLeavesNothing) {
  {
    auto txn = store_->BeginWrite();
    ASSERT_TRUE(txn.ok());
    ASSERT_TRUE((*txn)->InsertObservation(Batch("ghost", "s", 1)).ok());
  }  // rolled back here
  auto counts = store_->Counts();
  ASSERT_TRUE(counts.ok()) << counts.status().ToString();
  EXPECT_EQ(counts->robots, 0u);
  EXPECT_EQ(counts->observations, 0u);
  // The rolled-back robot must not linger in the cache either.
  EXPECT_TRUE(InsertOne(Batch("ghost", "s", 1))->stored);
  EXPECT_EQ(store_->Counts()->robots, 1u);
}

TEST_P(StoreConformanceTest, EverythingSurvivesAReopen) {
  ASSERT_TRUE(InsertOne(Batch("r1", "s1", 1)).ok());
  ASSERT_TRUE(InsertOne(Batch("r1", "s1", 2)).ok());
  {
    auto txn = store_->BeginWrite();
    FusedRow row;
    row.id = 7;
    row.segment = {{0, 0}, {3, 0}};
    row.support = 2;
    row.robots = "r1";
    ASSERT_TRUE((*txn)->UpsertFused(row).ok());
    ASSERT_TRUE((*txn)->Commit().ok());
  }
  Reopen();
  std::vector<StoredObservation> seen;
  ASSERT_TRUE(store_
                  ->ForEachObservation([&](const StoredObservation& o) {
                    seen.push_back(o);
                    return Status::Ok();
                  })
                  .ok());
  ASSERT_EQ(seen.size(), 2u);
  EXPECT_EQ(seen[0].seq, 1u);
  EXPECT_EQ(seen[1].seq, 2u);
  EXPECT_LT(seen[0].id, seen[1].id);
  EXPECT_EQ(seen[1].stamp_ns, 1002);
  EXPECT_EQ(seen[1].received_ns, 2002);
  ASSERT_EQ(seen[0].features.lines.size(), 2u);
  EXPECT_EQ(seen[0].features.lines[1].b, Eigen::Vector3d(3, 1, 0));
  EXPECT_EQ(seen[0].features.T_frame_sensor.translation, Eigen::Vector3d(1, 2, 0));
  auto fused = store_->LoadFused();
  ASSERT_TRUE(fused.ok());
  ASSERT_EQ(fused->size(), 1u);
  EXPECT_EQ((*fused)[0].id, 7u);
  EXPECT_EQ((*fused)[0].segment.a, Eigen::Vector2d(0, 0));
  EXPECT_EQ((*fused)[0].segment.b, Eigen::Vector2d(3, 0));
  EXPECT_EQ((*fused)[0].support, 2u);
  EXPECT_EQ((*fused)[0].robots, "r1");
  auto sessions = store_->ListSessions();
  ASSERT_TRUE(sessions.ok());
  ASSERT_EQ(sessions->size(), 1u);
  EXPECT_EQ((*sessions)[0].name, "s1");
  EXPECT_EQ(store_->FindSession("r1", "s1")->name, "s1");
  // And a duplicate is still recognised after the restart.
  EXPECT_FALSE(InsertOne(Batch("r1", "s1", 2))->stored);
}

TEST_F(StoreTest, RefusesADatabaseFromANewerMapd) {
  store_.reset();
  {
    auto db = OpenDatabase(dir_.File("map.db"), false);
    ASSERT_TRUE(db.ok());
    ASSERT_TRUE(Exec(db->get(), "INSERT INTO schema_version VALUES (999)").ok());
  }
  auto opened = SqliteStore::Open(dir_.File("map.db"), StoreOptions{});
  EXPECT_EQ(opened.status().code(), StatusCode::kFailedPrecondition);
  EXPECT_NE(opened.status().message().find("database schema version 999 is newer than this mapd"),
            std::string::npos)
      << opened.status().message();
}

TEST_F(StoreTest, RefusesAFileThatIsNotADatabase) {
  store_.reset();
  FILE* f = fopen(dir_.File("junk.db").c_str(), "w");
  fputs("this is not an SQLite database, just some text long enough to be read as a header...", f);
  fclose(f);
  auto opened = SqliteStore::Open(dir_.File("junk.db"), StoreOptions{});
  ASSERT_FALSE(opened.ok());
  // SQLite's own words, so that the operator knows it is the file, not mapd.
  EXPECT_NE(opened.status().message().find("file is not a database"), std::string::npos)
      << opened.status().message();
}

}  // namespace
}  // namespace mapd::storage

namespace mapd::storage {
namespace {

class StoreIdentityTest : public ::testing::Test {
 protected:
  // An SQLite file written by `sql`, as another application would.
  std::string ForeignDatabase(const std::string& name, const std::string& sql) {
    const std::string path = dir_.File(name);
    auto db = OpenDatabase(path, false);
    EXPECT_TRUE(db.ok());
    EXPECT_TRUE(Exec(db->get(), sql).ok());
    return path;
  }
  mapd::testing::TempDir dir_;
};

TEST_F(StoreIdentityTest, RefusesAnotherApplicationsDatabaseAndLeavesItAlone) {
  const std::string path = ForeignDatabase(
      "crm.db", "CREATE TABLE customers (id INTEGER); INSERT INTO customers VALUES (7)");
  auto opened = SqliteStore::Open(path, StoreOptions{});
  ASSERT_EQ(opened.status().code(), StatusCode::kFailedPrecondition);
  EXPECT_NE(opened.status().message().find("tables of another application (customers)"),
            std::string::npos)
      << opened.status().message();
  auto db = OpenDatabase(path, true);
  ASSERT_TRUE(db.ok());
  StatusOr<Statement> q =
      Statement::Prepare(db->get(), "SELECT count(*) FROM sqlite_master WHERE type = 'table'");
  ASSERT_TRUE(q.ok());
  ASSERT_TRUE(*q->Step());
  EXPECT_EQ(q->ColumnInt(0), 1) << "mapd added tables to a database it refused";
}

TEST_F(StoreIdentityTest, RefusesAForeignApplicationIdEvenWithoutTables) {
  const std::string path = ForeignDatabase("other.db", "PRAGMA application_id = 1234");
  auto opened = SqliteStore::Open(path, StoreOptions{});
  ASSERT_EQ(opened.status().code(), StatusCode::kFailedPrecondition);
  EXPECT_NE(opened.status().message().find("application_id is 0x000004d2"), std::string::npos)
      << opened.status().message();
}

TEST_F(StoreIdentityTest, StampsNewDatabasesAndAdoptsOnesFromBeforeTheStamp) {
  {
    auto store = SqliteStore::Open(dir_.File("map.db"), StoreOptions{});
    ASSERT_TRUE(store.ok()) << store.status().message();
  }
  auto db = OpenDatabase(dir_.File("map.db"), false);
  ASSERT_TRUE(db.ok());
  auto id = [&] {
    StatusOr<Statement> q = Statement::Prepare(db->get(), "PRAGMA application_id");
    EXPECT_TRUE(q.ok() && *q->Step());
    return static_cast<int32_t>(q->ColumnInt(0));
  };
  EXPECT_EQ(id(), kApplicationId);
  // A database of an earlier mapd carries no stamp: adopted and stamped.
  ASSERT_TRUE(Exec(db->get(), "PRAGMA application_id = 0").ok());
  EXPECT_EQ(id(), 0);
  ASSERT_TRUE(SqliteStore::Open(dir_.File("map.db"), StoreOptions{}).ok());
  EXPECT_EQ(id(), kApplicationId);
}

TEST_F(StoreIdentityTest, ASizeCapFailsWritesAsAFullDiskAndKeepsWhatWasCommitted) {
  StoreOptions options;
  options.max_db_bytes = 4 << 20;  // room for the 1 MiB probe at first
  auto store = SqliteStore::Open(dir_.File("map.db"), options);
  ASSERT_TRUE(store.ok()) << store.status().message();
  EXPECT_TRUE((*store)->ProbeWrite().ok());
  geometry::SensorObservation features;
  for (int i = 0; i < 200; ++i) features.lines.push_back({{0, 0, 0}, {1.0 * i, 1, 0}});
  Status failure;
  uint64_t committed = 0;
  for (uint64_t seq = 1; seq < 10000 && failure.ok(); ++seq) {
    auto txn = (*store)->BeginWrite();
    ASSERT_TRUE(txn.ok());
    NewObservation o;
    o.robot = "r1";
    o.session = "s1";
    o.seq = seq;
    o.features = &features;
    StatusOr<InsertResult> r = (*txn)->InsertObservation(o);
    failure = r.ok() ? (*txn)->Commit() : r.status();
    if (failure.ok()) committed = seq;
  }
  EXPECT_EQ(failure.code(), StatusCode::kResourceExhausted) << failure.message();
  EXPECT_NE(failure.message().find("full"), std::string::npos) << failure.message();
  EXPECT_GT(committed, 0u);
  EXPECT_EQ((*store)->ProbeWrite().code(), StatusCode::kResourceExhausted);
  store->reset();
  auto reopened = SqliteStore::Open(dir_.File("map.db"), StoreOptions{});
  ASSERT_TRUE(reopened.ok());
  uint64_t kept = 0;
  ASSERT_TRUE((*reopened)
                  ->ForEachObservation([&](const StoredObservation&) {
                    ++kept;
                    return Status::Ok();
                  })
                  .ok());
  EXPECT_EQ(kept, committed);
  EXPECT_TRUE((*reopened)->ProbeWrite().ok());
}

MAPD_ON_EVERY_BACKEND(StoreConformanceTest);

}  // namespace
}  // namespace mapd::storage
