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

MAPD_ON_EVERY_BACKEND(PlaneStoreConformanceTest);

}  // namespace
}  // namespace mapd::storage
