// Map leases on a real PostgreSQL (storage/postgres/map_lease.h): one owner
// at a time, takeover once a lease lapses, and the fence that keeps a paused
// owner ("zombie") from committing after a takeover.
#include "storage/postgres/map_lease.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <chrono>
#include <future>
#include <memory>
#include <string>
#include <thread>

#include "common/postgres.h"
#include "storage/postgres/schema.h"
#include "storage/postgres/store.h"

namespace mapd::storage {
namespace {

using ::testing::HasSubstr;

const PgInstance kA{"mapd-a", "10.0.0.1:50051"};
const PgInstance kB{"mapd-b", "10.0.0.2:50051"};

void Sleep(double s) { std::this_thread::sleep_for(std::chrono::duration<double>(s)); }

class MapLeaseTest : public ::testing::Test {
 protected:
  void SetUp() override {
    cluster_ = mapd::testing::PostgresCluster::Shared();
    if (cluster_ == nullptr) GTEST_SKIP() << "no PostgreSQL (install postgresql-15)";
    conninfo_ = cluster_->NewDatabase();
    conn_ = Connect();
    ASSERT_TRUE(MigratePostgres(conn_).ok());
    ASSERT_TRUE(EnsureMap(conn_, "site-1", 1).ok());
    features_.lines.push_back({{0, 0, 0}, {2, 0, 0}});
  }

  PgConnection Connect() {
    StatusOr<PgConnection> c = PgConnection::Connect(conninfo_);
    EXPECT_TRUE(c.ok()) << c.status().ToString();
    return c.ok() ? std::move(c).value() : PgConnection();
  }

  std::unique_ptr<PgStore> OpenStore(const PgInstance& who, double ttl_s = 10,
                                     double idle_in_transaction_s = 10) {
    PgOwnership o;
    o.instance = who;
    o.lease_ttl_s = ttl_s;
    o.idle_in_transaction_s = idle_in_transaction_s;
    StatusOr<std::unique_ptr<PgStore>> s = PgStore::Open(conninfo_, "site-1", StoreOptions{}, o);
    EXPECT_TRUE(s.ok()) << s.status().ToString();
    return s.ok() ? std::move(s).value() : nullptr;
  }

  NewObservation Batch(const std::string& robot, uint64_t seq) {
    NewObservation o;
    o.robot = robot;
    o.session = "s1";
    o.seq = seq;
    o.features = &features_;
    return o;
  }

  // One batch in a transaction of its own: the observation's id.
  StatusOr<int64_t> Insert(Store& store, const std::string& robot, uint64_t seq) {
    StatusOr<std::unique_ptr<WriteTransaction>> txn = store.BeginWrite();
    if (!txn.ok()) return txn.status();
    StatusOr<InsertResult> r = (*txn)->InsertObservation(Batch(robot, seq));
    if (!r.ok()) return r.status();
    MAPD_RETURN_IF_ERROR((*txn)->Commit());
    return r->observation_id;
  }

  mapd::testing::PostgresCluster* cluster_ = nullptr;
  std::string conninfo_;
  PgConnection conn_;
  geometry::SensorObservation features_;
};

TEST_F(MapLeaseTest, OneOwnerAtATimeAndEachTakeBumpsTheEpoch) {
  StatusOr<MapLease> a = AcquireMapLease(conn_, "site-1", kA, 10);
  ASSERT_TRUE(a.ok()) << a.status().ToString();
  EXPECT_EQ(a->epoch, 1);
  StatusOr<MapLease> b = AcquireMapLease(conn_, "site-1", kB, 10);
  EXPECT_EQ(b.status().code(), StatusCode::kFailedPrecondition);
  EXPECT_THAT(b.status().message(),
              HasSubstr("served by instance 'mapd-a' (10.0.0.1:50051, epoch 1)"));
  EXPECT_TRUE(RenewMapLease(conn_, *a, 10).ok());

  ASSERT_TRUE(ReleaseMapLease(conn_, *a).ok());
  b = AcquireMapLease(conn_, "site-1", kB, 10);
  ASSERT_TRUE(b.ok()) << b.status().ToString();
  EXPECT_EQ(b->epoch, 2);
  const Status lost = RenewMapLease(conn_, *a, 10);
  EXPECT_EQ(lost.code(), StatusCode::kFailedPrecondition);
  EXPECT_THAT(lost.message(), HasSubstr("taken over; instance 'mapd-b' (10.0.0.2:50051, epoch 2)"));

  StatusOr<LeaseRow> row = GetMapLease(conn_, "site-1");
  ASSERT_TRUE(row.ok());
  EXPECT_EQ(row->owner, "mapd-b");
  EXPECT_EQ(row->address, "10.0.0.2:50051");
  EXPECT_GT(row->expires_in_s, 9);
  EXPECT_EQ(GetMapLease(conn_, "site-2").status().code(), StatusCode::kNotFound);
}

TEST_F(MapLeaseTest, ALapsedLeaseIsTakenAndARestartedOwnerTakesItsOwnAtOnce) {
  StatusOr<MapLease> a = AcquireMapLease(conn_, "site-1", kA, 0.2);
  ASSERT_TRUE(a.ok());
  StatusOr<MapLease> again = AcquireMapLease(conn_, "site-1", kA, 10);  // same name: a restart
  ASSERT_TRUE(again.ok()) << again.status().ToString();
  EXPECT_EQ(again->epoch, 2);
  EXPECT_FALSE(AcquireMapLease(conn_, "site-1", kB, 10).ok());
  ASSERT_TRUE(RenewMapLease(conn_, *again, 0.2).ok());
  Sleep(0.3);  // lapsed, on the database's clock
  StatusOr<MapLease> b = AcquireMapLease(conn_, "site-1", kB, 10);
  ASSERT_TRUE(b.ok()) << b.status().ToString();
  EXPECT_EQ(b->epoch, 3);
}

TEST_F(MapLeaseTest, ARenewalAfterTheLeaseLapsedHoldsWhileNobodyTookIt) {
  StatusOr<MapLease> a = AcquireMapLease(conn_, "site-1", kA, 0.1);
  ASSERT_TRUE(a.ok());
  Sleep(0.2);
  EXPECT_TRUE(RenewMapLease(conn_, *a, 10).ok());
  EXPECT_FALSE(AcquireMapLease(conn_, "site-1", kB, 10).ok());
}

// The zombie: an owner that was paused past its lease wakes after another
// took the map. Its next transaction is refused, it stops owning the map, and
// every row it stored precedes the new owner's.
TEST_F(MapLeaseTest, APausedOwnerCannotCommitAfterATakeover) {
  std::unique_ptr<PgStore> zombie = OpenStore(kA, /*ttl_s=*/0.2);
  ASSERT_NE(zombie, nullptr);
  StatusOr<int64_t> before = Insert(*zombie, "r1", 1);
  ASSERT_TRUE(before.ok()) << before.status().ToString();
  Sleep(0.3);  // paused past the lease
  std::unique_ptr<PgStore> owner = OpenStore(kB);
  ASSERT_NE(owner, nullptr);
  EXPECT_EQ(owner->lease().epoch, 2);
  StatusOr<int64_t> after = Insert(*owner, "r1", 2);
  ASSERT_TRUE(after.ok()) << after.status().ToString();

  StatusOr<int64_t> woke = Insert(*zombie, "r1", 3);
  EXPECT_EQ(woke.status().code(), StatusCode::kFailedPrecondition);
  EXPECT_THAT(woke.status().message(), HasSubstr("taken over; instance 'mapd-b'"));
  EXPECT_FALSE(zombie->owner());
  EXPECT_EQ(zombie->ProbeWrite().code(), StatusCode::kFailedPrecondition);
  EXPECT_GT(*after, *before);
  auto robots = owner->ListRobots();
  ASSERT_TRUE(robots.ok());
  EXPECT_EQ((*robots)[0].batches, 2u) << "the zombie's third batch is not stored";
  // Closing the zombie does not end the new owner's lease.
  zombie.reset();
  EXPECT_FALSE(AcquireMapLease(conn_, "site-1", {"mapd-c", ""}, 10).ok());
  EXPECT_TRUE(RenewMapLease(conn_, owner->lease(), 10).ok());
}

// A takeover waits for the owner's open transaction (the fence's row lock),
// so the old epoch's last commit precedes the new epoch's first.
TEST_F(MapLeaseTest, ATakeoverWaitsForTheOwnersOpenTransaction) {
  std::unique_ptr<PgStore> old_owner = OpenStore(kA, /*ttl_s=*/0.2);
  ASSERT_NE(old_owner, nullptr);
  StatusOr<std::unique_ptr<WriteTransaction>> txn = old_owner->BeginWrite();
  ASSERT_TRUE(txn.ok()) << txn.status().ToString();
  StatusOr<InsertResult> in_flight = (*txn)->InsertObservation(Batch("r1", 1));
  ASSERT_TRUE(in_flight.ok());
  Sleep(0.3);  // the lease lapses while the transaction is open
  std::future<std::unique_ptr<PgStore>> taking =
      std::async(std::launch::async, [&] { return OpenStore(kB); });
  EXPECT_EQ(taking.wait_for(std::chrono::milliseconds(500)), std::future_status::timeout)
      << "the take must wait for the open transaction";
  ASSERT_TRUE((*txn)->Commit().ok()) << "the old epoch's open transaction still commits";
  txn->reset();
  std::unique_ptr<PgStore> new_owner = taking.get();
  ASSERT_NE(new_owner, nullptr);
  StatusOr<int64_t> first_new = Insert(*new_owner, "r1", 2);
  ASSERT_TRUE(first_new.ok()) << first_new.status().ToString();
  EXPECT_GT(*first_new, in_flight->observation_id);
  EXPECT_EQ(Insert(*old_owner, "r1", 3).status().code(), StatusCode::kFailedPrecondition);
}

// A paused owner's open transaction holds a takeover back only until
// PostgreSQL ends its idle session (idle_in_transaction_s).
TEST_F(MapLeaseTest, APausedOwnersOpenTransactionIsEndedByPostgres) {
  std::unique_ptr<PgStore> paused = OpenStore(kA, /*ttl_s=*/0.2, /*idle_in_transaction_s=*/0.5);
  ASSERT_NE(paused, nullptr);
  StatusOr<std::unique_ptr<WriteTransaction>> txn = paused->BeginWrite();
  ASSERT_TRUE(txn.ok());
  ASSERT_TRUE((*txn)->InsertObservation(Batch("r1", 1)).ok());
  // ... and the owner sleeps with the transaction open.
  const auto start = std::chrono::steady_clock::now();
  std::unique_ptr<PgStore> taker = OpenStore(kB);
  ASSERT_NE(taker, nullptr);
  EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(), 5.0);
  EXPECT_FALSE((*txn)->Commit().ok()) << "PostgreSQL ended the paused session";
  auto robots = taker->ListRobots();
  ASSERT_TRUE(robots.ok());
  EXPECT_TRUE(robots->empty()) << "nothing of the paused transaction is stored";
}

TEST_F(MapLeaseTest, InstancesAreLiveWhileTheyHeartbeat) {
  ASSERT_TRUE(HeartbeatInstance(conn_, kA, 10).ok());
  ASSERT_TRUE(HeartbeatInstance(conn_, kB, 0.2).ok());
  StatusOr<std::vector<InstanceRow>> live = LiveInstances(conn_);
  ASSERT_TRUE(live.ok());
  ASSERT_EQ(live->size(), 2u);
  EXPECT_EQ((*live)[0].name, "mapd-a");
  EXPECT_EQ((*live)[0].address, "10.0.0.1:50051");
  Sleep(0.3);
  live = LiveInstances(conn_);
  ASSERT_EQ(live->size(), 1u) << "mapd-b stopped heartbeating";
  ASSERT_TRUE(LeaveInstance(conn_, kA).ok());
  EXPECT_TRUE(LiveInstances(conn_)->empty());
}

TEST_F(MapLeaseTest, AClosedStoreHoldsNoConnectionAndRefusesEverything) {
  auto sessions = [&] {
    StatusOr<PgResult> r =
        conn_.Query("SELECT count(*) FROM pg_stat_activity WHERE datname = current_database()");
    return r.ok() ? static_cast<int>(r->Int(0, 0)) : -1;
  };
  const int before = sessions();
  std::unique_ptr<PgStore> store = OpenStore(kA);
  ASSERT_NE(store, nullptr);
  ASSERT_TRUE(Insert(*store, "r1", 1).ok());
  ASSERT_TRUE(store->ListRobots().ok());
  EXPECT_GT(sessions(), before);

  // Handed off: the lease is released and both connections are closed.
  store->Close(Status::Unavailable("map 'site-1' is no longer served here"));
  for (int i = 0; i < 50 && sessions() > before; ++i) Sleep(0.02);
  EXPECT_EQ(sessions(), before) << "a map handed off holds no connection";
  for (const Status& s :
       {store->ListRobots().status(), store->ProbeWrite(), Insert(*store, "r1", 2).status()}) {
    EXPECT_EQ(s.code(), StatusCode::kUnavailable) << s.ToString();
    EXPECT_THAT(s.message(), HasSubstr("no longer served here")) << s.ToString();
  }
  // Nothing connected again, and another instance takes the map at once.
  EXPECT_EQ(sessions(), before);
  std::unique_ptr<PgStore> taker = OpenStore(kB);
  ASSERT_NE(taker, nullptr);
  auto robots = taker->ListRobots();
  ASSERT_TRUE(robots.ok());
  EXPECT_EQ((*robots)[0].batches, 1u);
}

TEST_F(MapLeaseTest, ACommitThatLandedWhileItsAnswerWasLostMakesTheStoreGiveTheMapUp) {
  std::unique_ptr<PgStore> store = OpenStore(kA);
  ASSERT_NE(store, nullptr);
  ASSERT_TRUE(Insert(*store, "r1", 1).ok());
  // As if PostgreSQL crashed after committing the store's next transaction
  // but before answering: the row is there, the store never heard of it.
  ASSERT_TRUE(conn_
                  .Exec("INSERT INTO observations SELECT map, id + 1, session_id, seq + 1, "
                        "stamp_ns, received_ns, qw, qx, qy, qz, tx, ty, tz, line_count, "
                        "plane_count, payload FROM observations WHERE map = 'site-1' AND id = 1")
                  .ok());
  ASSERT_TRUE(conn_
                  .Exec("SELECT pg_terminate_backend(pid) FROM pg_stat_activity WHERE datname = "
                        "current_database() AND pid <> pg_backend_pid()")
                  .ok());
  const Status probe = store->ProbeWrite();
  EXPECT_EQ(probe.code(), StatusCode::kFailedPrecondition) << probe.ToString();
  EXPECT_THAT(probe.message(), HasSubstr("did land (1 observations)"));
  EXPECT_FALSE(store->owns_map()) << "the engine is out of step: the map must be opened again";
  EXPECT_FALSE(Insert(*store, "r1", 3).ok()) << "no write on stale ids";
  // The same instance opens it again at once (its lease) and writes on.
  store.reset();
  std::unique_ptr<PgStore> again = OpenStore(kA);
  ASSERT_NE(again, nullptr);
  auto newest = again->NewestObservationId();
  ASSERT_TRUE(newest.ok());
  EXPECT_EQ(*newest, 2);
  auto next = Insert(*again, "r1", 3);
  ASSERT_TRUE(next.ok()) << next.status().ToString();
  EXPECT_EQ(*next, 3);
}

}  // namespace
}  // namespace mapd::storage
