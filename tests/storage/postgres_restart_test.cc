// A PostgreSQL restart under a map's store: writes fail while it is away
// (nothing is acknowledged that is not stored), the store connects again by
// itself when mapd probes, and a map another mapd took over meanwhile is
// refused.
// Each test runs its own cluster, with fsync on, since it stops it.
#include <gtest/gtest.h>

#include <chrono>
#include <memory>
#include <string>
#include <thread>

#include "common/postgres.h"
#include "storage/postgres/store.h"

namespace mapd::storage {
namespace {

class PostgresRestartTest : public ::testing::Test {
 protected:
  void SetUp() override {
    std::string why;
    cluster_ = mapd::testing::PostgresCluster::Start(/*fsync=*/true, &why);
    if (cluster_ == nullptr) GTEST_SKIP() << "no PostgreSQL (install postgresql-15): " << why;
    conninfo_ = cluster_->NewDatabase();
    features_.lines.push_back({{0, 0, 0}, {2, 0, 0}});
  }

  std::unique_ptr<Store> Open(const std::string& instance = "mapd-a", double lease_ttl_s = 10) {
    PgOwnership ownership;
    ownership.instance = {instance, instance + ":50051"};
    ownership.lease_ttl_s = lease_ttl_s;
    StatusOr<std::unique_ptr<PgStore>> s =
        PgStore::Open(conninfo_, "site-1", StoreOptions{}, ownership);
    EXPECT_TRUE(s.ok()) << s.status().ToString();
    return s.ok() ? std::move(s).value() : nullptr;
  }

  StatusOr<InsertResult> Insert(Store& store, uint64_t seq) {
    StatusOr<std::unique_ptr<WriteTransaction>> txn = store.BeginWrite();
    if (!txn.ok()) return txn.status();
    NewObservation o;
    o.robot = "r1";
    o.session = "s1";
    o.seq = seq;
    o.features = &features_;
    StatusOr<InsertResult> r = (*txn)->InsertObservation(o);
    if (!r.ok()) return r;
    MAPD_RETURN_IF_ERROR((*txn)->Commit());
    return r;
  }

  std::unique_ptr<mapd::testing::PostgresCluster> cluster_;
  std::string conninfo_;
  geometry::SensorObservation features_;
};

TEST_F(PostgresRestartTest, TheStoreConnectsAgainWhenPostgresComesBack) {
  std::unique_ptr<Store> store = Open();
  ASSERT_NE(store, nullptr);
  auto first = Insert(*store, 1);
  ASSERT_TRUE(first.ok()) << first.status().ToString();

  ASSERT_TRUE(cluster_->Stop("fast"));
  auto away = Insert(*store, 2);
  EXPECT_EQ(away.status().code(), StatusCode::kUnavailable) << away.status().ToString();
  EXPECT_EQ(store->ProbeWrite().code(), StatusCode::kUnavailable);

  std::string why;
  ASSERT_TRUE(cluster_->Restart(&why)) << why;
  Status probe = store->ProbeWrite();
  ASSERT_TRUE(probe.ok()) << probe.ToString();
  auto again = Insert(*store, 2);
  ASSERT_TRUE(again.ok()) << again.status().ToString();
  EXPECT_TRUE(again->stored);
  EXPECT_EQ(again->observation_id, first->observation_id + 1);
  auto resend = Insert(*store, 1);
  ASSERT_TRUE(resend.ok());
  EXPECT_FALSE(resend->stored);
  // Reads connect again by themselves too.
  auto robots = store->ListRobots();
  ASSERT_TRUE(robots.ok()) << robots.status().ToString();
  EXPECT_EQ((*robots)[0].batches, 2u);
  // And it still holds the map: another instance is refused.
  PgOwnership b;
  b.instance = {"mapd-b", ""};
  auto second = PgStore::Open(conninfo_, "site-1", StoreOptions{}, b);
  EXPECT_EQ(second.status().code(), StatusCode::kFailedPrecondition);
}

TEST_F(PostgresRestartTest, AMapTakenOverMeanwhileIsRefused) {
  std::unique_ptr<Store> store = Open("mapd-a", /*lease_ttl_s=*/0.5);
  ASSERT_NE(store, nullptr);
  ASSERT_TRUE(Insert(*store, 1).ok());
  ASSERT_TRUE(cluster_->Stop("immediate"));  // a crash
  std::string why;
  ASSERT_TRUE(cluster_->Restart(&why)) << why;
  // A read after a crash connects again by itself (libpq reports the dead
  // connection without a SQLSTATE and does not always mark it broken).
  auto robots = store->ListRobots();
  ASSERT_TRUE(robots.ok()) << robots.status().ToString();
  EXPECT_EQ((*robots)[0].batches, 1u);
  std::this_thread::sleep_for(std::chrono::milliseconds(600));  // the lease lapses
  {
    std::unique_ptr<Store> other = Open("mapd-b");  // another mapd takes the map
    ASSERT_NE(other, nullptr);
    ASSERT_TRUE(Insert(*other, 2).ok());
  }
  EXPECT_FALSE(Insert(*store, 3).ok());  // the broken connection
  const Status probe = store->ProbeWrite();
  EXPECT_EQ(probe.code(), StatusCode::kFailedPrecondition) << probe.ToString();
  EXPECT_NE(probe.message().find("taken over by instance 'mapd-b'"), std::string::npos)
      << probe.ToString();
  const auto refused = Insert(*store, 3);
  EXPECT_EQ(refused.status().code(), StatusCode::kFailedPrecondition);
}

}  // namespace
}  // namespace mapd::storage
