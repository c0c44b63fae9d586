// Fused plane rows and the plane engine's part of a snapshot (schema 5).
#include <gtest/gtest.h>

#include "storage/store.h"
#include "storage/support/store_fixture.h"

namespace mapd::storage {
namespace {

class PlaneStoreTest : public testing::StoreFixture {};

using PlaneStoreConformanceTest = testing::OnEveryBackend<PlaneStoreTest>;

TEST_P(PlaneStoreConformanceTest, FusedPlaneRowsSurviveAReopenAndCanBeDeleted) {
  FusedPlaneRow row;
  row.id = 4097;
  row.normal = {0, 0, 1};
  row.offset_m = -0.25;
  row.boundary = {{0, 0, 0.25}, {4, 0, 0.25}, {4, 3, 0.25}, {0, 3, 0.25}};
  row.area_m2 = 12;
  row.z_min_m = row.z_max_m = 0.25;
  row.support = 3;
  row.member_count = 5;
  row.robots = "r1,r2";
  FusedPlaneRow other = row;
  other.id = 9000;
  {
    auto txn = store_->BeginWrite();
    ASSERT_TRUE(txn.ok());
    ASSERT_TRUE((*txn)->UpsertFusedPlane(row).ok());
    ASSERT_TRUE((*txn)->UpsertFusedPlane(other).ok());
    ASSERT_TRUE((*txn)->DeleteFusedPlane(9000).ok());
    ASSERT_TRUE((*txn)->Commit().ok());
  }
  Reopen();
  auto planes = store_->LoadFusedPlanes();
  ASSERT_TRUE(planes.ok()) << planes.status().ToString();
  ASSERT_EQ(planes->size(), 1u);
  const FusedPlaneRow& r = (*planes)[0];
  EXPECT_EQ(r.id, 4097u);
  EXPECT_EQ(r.normal, row.normal);
  EXPECT_EQ(r.offset_m, -0.25);
  EXPECT_EQ(r.boundary, row.boundary);
  EXPECT_EQ(r.area_m2, 12);
  EXPECT_EQ(r.support, 3u);
  EXPECT_EQ(r.member_count, 5u);
  EXPECT_EQ(r.robots, "r1,r2");
}

TEST_P(PlaneStoreConformanceTest, SnapshotsCarryThePlaneStateOrSayTheyHaveNone) {
  FusionSnapshot with;
  with.state = "lines";
  with.plane_state = "planes";
  with.has_plane_state = true;
  FusionSnapshot without;  // as written before schema 5
  without.state = "lines only";
  {
    auto txn = store_->BeginWrite();
    ASSERT_TRUE((*txn)->InsertSnapshot(with, 2).ok());
    ASSERT_TRUE((*txn)->InsertSnapshot(without, 2).ok());
    ASSERT_TRUE((*txn)->Commit().ok());
  }
  auto newest = store_->LatestSnapshot(0);
  ASSERT_TRUE(newest.ok());
  EXPECT_FALSE(newest->has_plane_state);
  auto older = store_->LatestSnapshot(1);
  ASSERT_TRUE(older.ok());
  EXPECT_TRUE(older->has_plane_state);
  EXPECT_EQ(older->plane_state, "planes");
  EXPECT_EQ(older->state, "lines");
}

// A commit's fused changes at once (WriteFused, WriteFusedPlanes) leave the
// rows one row at a time would: upserts replace, deletes remove.
TEST_P(PlaneStoreConformanceTest, FusedChangesAtOnceAsOneByOne) {
  std::vector<FusedRow> lines(3);
  for (size_t i = 0; i < lines.size(); ++i) {
    lines[i].id = 10 + i;
    lines[i].segment = {{0.0 + i, 1}, {2.0 + i, 1.0 / 3.0}};
    lines[i].z_min_m = -0.1;
    lines[i].z_max_m = 2.5;
    lines[i].support = 3;
    lines[i].member_count = 4;
    lines[i].robots = "r1,r2";
  }
  FusedPlaneRow plane;
  plane.id = 7;
  plane.normal = {0, 0, 1};
  plane.offset_m = -0.25;
  plane.boundary = {{0, 0, 0.25}, {1, 0, 0.25}, {1, 1, 0.25}};
  plane.area_m2 = 0.5;
  plane.support = 2;
  plane.robots = "r1";
  ASSERT_TRUE(Write([&](WriteTransaction* t) {
                MAPD_RETURN_IF_ERROR(t->WriteFused(lines, {}));
                return t->WriteFusedPlanes({plane}, {});
              }).ok());
  lines[1].support = 9;
  lines[1].segment.b = {5, 5};
  plane.area_m2 = 0.75;
  ASSERT_TRUE(Write([&](WriteTransaction* t) {
                MAPD_RETURN_IF_ERROR(t->WriteFused({lines[1]}, {10, 12, 99}));
                return t->WriteFusedPlanes({plane}, {});
              }).ok());
  Reopen();
  auto rows = store_->LoadFused();
  ASSERT_TRUE(rows.ok()) << rows.status().ToString();
  ASSERT_EQ(rows->size(), 1u);
  EXPECT_EQ((*rows)[0].id, 11u);
  EXPECT_EQ((*rows)[0].support, 9u);
  EXPECT_EQ((*rows)[0].segment.a, lines[1].segment.a);
  EXPECT_EQ((*rows)[0].segment.b, lines[1].segment.b);
  EXPECT_EQ((*rows)[0].robots, "r1,r2");
  auto planes = store_->LoadFusedPlanes();
  ASSERT_TRUE(planes.ok());
  ASSERT_EQ(planes->size(), 1u);
  EXPECT_EQ((*planes)[0].area_m2, 0.75);
  EXPECT_EQ((*planes)[0].boundary, plane.boundary);
  ASSERT_TRUE(Write([&](WriteTransaction* t) { return t->WriteFusedPlanes({}, {7}); }).ok());
  EXPECT_TRUE(store_->LoadFusedPlanes()->empty());
}

MAPD_ON_EVERY_BACKEND(PlaneStoreConformanceTest);

}  // namespace
}  // namespace mapd::storage
