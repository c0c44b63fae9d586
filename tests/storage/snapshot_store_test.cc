// Fusion snapshots in the store, whole or in parts (storage/store.h).
#include <gtest/gtest.h>

#include <string>
#include <string_view>
#include <vector>

#include "storage/store.h"
#include "storage/support/store_fixture.h"

namespace mapd::storage {
namespace {

class SnapshotStoreTest : public testing::StoreFixture {
 protected:
  static FusionSnapshot Snapshot(std::string state, std::string plane_state, bool has_planes) {
    FusionSnapshot s;
    s.created_ns = 7;
    s.map_version = 11;
    s.through_observation = 13;
    s.through_tie_seq = 2;
    s.params = "params";
    s.state = std::move(state);
    s.plane_state = std::move(plane_state);
    s.has_plane_state = has_planes;
    return s;
  }

  // Writes `snap` as MapCore does: each part in a transaction of its own,
  // then the row.
  void WriteInParts(const FusionSnapshot& snap, int64_t key, size_t part_bytes, int keep = 2) {
    const std::vector<std::string_view> parts = SnapshotPartsOf(snap, part_bytes);
    for (size_t i = 0; i < parts.size(); ++i) {
      ASSERT_TRUE(Write([&](WriteTransaction* txn) {
                    return txn->InsertSnapshotPart(key, static_cast<int>(i), parts[i]);
                  }).ok());
    }
    ASSERT_TRUE(Write([&](WriteTransaction* txn) {
                  return txn->InsertSnapshot(snap, keep,
                                             SnapshotParts{key, static_cast<int>(parts.size())});
                }).ok());
  }

  int CountParts() { return static_cast<int>(CountRows("fusion_snapshot_parts")); }
};

using SnapshotStoreConformanceTest = testing::OnEveryBackend<SnapshotStoreTest>;

TEST_P(SnapshotStoreConformanceTest, PartsNeverSpanStateAndPlaneState) {
  const FusionSnapshot snap = Snapshot("abcdefg", "xyz", true);
  const std::vector<std::string_view> parts = SnapshotPartsOf(snap, 3);
  EXPECT_EQ(parts, (std::vector<std::string_view>{"abc", "def", "g", "xyz"}));
  EXPECT_TRUE(SnapshotPartsOf(Snapshot("", "", false), 3).empty());
}

TEST_P(SnapshotStoreConformanceTest, ASnapshotInPartsReadsBackWhole) {
  const FusionSnapshot snap = Snapshot("the line engine's state", "planes", true);
  WriteInParts(snap, 42, 4);
  Reopen();
  auto read = store_->LatestSnapshot();
  ASSERT_TRUE(read.ok()) << read.status().ToString();
  EXPECT_EQ(read->state, snap.state);
  EXPECT_TRUE(read->has_plane_state);
  EXPECT_EQ(read->plane_state, snap.plane_state);
  EXPECT_EQ(read->map_version, 11u);
  EXPECT_EQ(read->through_observation, 13);
  EXPECT_EQ(read->through_tie_seq, 2);
  EXPECT_EQ(read->params, "params");
}

TEST_P(SnapshotStoreConformanceTest, ASnapshotInPartsWithoutPlaneStateSaysSo) {
  WriteInParts(Snapshot("lines only", "", false), 5, 3);
  auto read = store_->LatestSnapshot();
  ASSERT_TRUE(read.ok()) << read.status().ToString();
  EXPECT_EQ(read->state, "lines only");
  EXPECT_FALSE(read->has_plane_state);
}

TEST_F(SnapshotStoreTest, AMissingPartIsAnErrorNamingIt) {
  WriteInParts(Snapshot("0123456789", "p", true), 9, 2);
  {
    auto db = OpenDatabase(dir_.File("map.db"), false);
    ASSERT_TRUE(db.ok());
    ASSERT_TRUE(Exec(db->get(), "DELETE FROM fusion_snapshot_parts WHERE part = 2").ok());
  }
  auto read = store_->LatestSnapshot();
  ASSERT_FALSE(read.ok());
  EXPECT_EQ(read.status().code(), StatusCode::kInternal);
  EXPECT_NE(read.status().message().find("2 of its 6 parts"), std::string::npos)
      << read.status().message();
}

TEST_P(SnapshotStoreConformanceTest, PartsOfPrunedOrUnfinishedSnapshotsAreDeletedInRounds) {
  WriteInParts(Snapshot("aaaaaa", "", false), 1, 1, /*keep=*/1);  // 6 parts, pruned below
  // An interrupted snapshot: parts, no row.
  ASSERT_TRUE(
      Write([](WriteTransaction* txn) { return txn->InsertSnapshotPart(2, 0, "orphan"); }).ok());
  WriteInParts(Snapshot("bbbb", "", false), 3, 2, /*keep=*/1);  // 2 parts, kept
  ASSERT_EQ(CountParts(), 9);
  int deleted = 0;
  for (;;) {
    StatusOr<int> n = 0;
    ASSERT_TRUE(Write([&](WriteTransaction* txn) {
                  n = txn->DeleteUnusedSnapshotParts(4);
                  return n.status();
                }).ok());
    ASSERT_TRUE(n.ok());
    EXPECT_LE(*n, 4);
    deleted += *n;
    if (*n < 4) break;
  }
  EXPECT_EQ(deleted, 7);
  EXPECT_EQ(CountParts(), 2);
  auto read = store_->LatestSnapshot();
  ASSERT_TRUE(read.ok()) << read.status().ToString();
  EXPECT_EQ(read->state, "bbbb");
  EXPECT_EQ(store_->LatestSnapshot(1).status().code(), StatusCode::kNotFound);
}

// A database of schema 8 (snapshots in their rows) opens, its snapshot reads
// as before, and the next one may be written in parts.
TEST_F(SnapshotStoreTest, ASnapshotOfAnOlderDatabaseReadsUnchanged) {
  ASSERT_TRUE(Write([](WriteTransaction* txn) {
                return txn->InsertSnapshot(Snapshot("whole", "planes", true), 2);
              }).ok());
  DowngradeAndReopen(std::string(testing::kUndoSnapshotParts) +
                     "DELETE FROM schema_version WHERE version >= 9");
  auto old = store_->LatestSnapshot();
  ASSERT_TRUE(old.ok()) << old.status().ToString();
  EXPECT_EQ(old->state, "whole");
  EXPECT_EQ(old->plane_state, "planes");
  WriteInParts(Snapshot("newer", "", false), 4, 2);
  auto newest = store_->LatestSnapshot();
  ASSERT_TRUE(newest.ok()) << newest.status().ToString();
  EXPECT_EQ(newest->state, "newer");
  auto before = store_->LatestSnapshot(1);
  ASSERT_TRUE(before.ok());
  EXPECT_EQ(before->state, "whole");
}

MAPD_ON_EVERY_BACKEND(SnapshotStoreConformanceTest);

}  // namespace
}  // namespace mapd::storage
