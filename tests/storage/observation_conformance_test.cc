// The observation intent's contract, on every backend (SQLite, PostgreSQL):
// idempotent batches, frame kinds, transactions, ties, reads and restarts.
// PostgreSQL-only: several maps share one database and stay apart, and
// several mapd migrating an empty database at once do it once.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <thread>
#include <vector>

#include "storage/postgres/map_catalog.h"
#include "storage/postgres/store.h"
#include "storage/support/observation_backends.h"

namespace mapd::storage {
namespace {

using testing::ObservationBackend;

std::unique_ptr<ObservationBackend> MakeBackend(const std::string& name) {
  if (name == "sqlite") return std::make_unique<testing::SqliteObservationBackend>();
  mapd::testing::PostgresCluster* cluster = mapd::testing::PostgresCluster::Shared();
  if (cluster == nullptr) return nullptr;
  return std::make_unique<testing::PostgresObservationBackend>(cluster->NewDatabase(), "site-1");
}

class ObservationConformanceTest : public ::testing::TestWithParam<std::string> {
 protected:
  void SetUp() override {
    backend_ = MakeBackend(GetParam());
    if (backend_ == nullptr) GTEST_SKIP() << "no PostgreSQL (install postgresql-15)";
    Status s = backend_->Reopen();
    ASSERT_TRUE(s.ok()) << s.ToString();
  }

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
    StatusOr<InsertResult> result = Status::Internal("not run");
    Status s = backend_->Write([&](ObservationWriter& w) {
      result = w.InsertObservation(o);
      return result.status();
    });
    if (!s.ok()) return s;
    return result;
  }

  std::vector<StoredObservation> All() {
    std::vector<StoredObservation> out;
    Status s = backend_->reader().ForEachObservation([&](const StoredObservation& o) {
      out.push_back(o);
      return Status::Ok();
    });
    EXPECT_TRUE(s.ok()) << s.ToString();
    return out;
  }

  geometry::SensorObservation features_ = [] {
    geometry::SensorObservation f;
    f.T_frame_sensor.translation = {1, 2, 0.25};
    f.T_frame_sensor.rotation =
        Eigen::Quaterniond(Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitZ()));
    f.lines.push_back({{0, 0, 0}, {3, 0, 0}});
    f.lines.push_back({{0, 1, 0}, {3, 1, 1.0 / 3.0}});
    geometry::PlaneFeature plane;
    plane.normal = Eigen::Vector3d::UnitZ();
    plane.offset = -0.5;
    plane.boundary = {{0, 0, 0.5}, {1, 0, 0.5}, {1, 1, 0.5}};
    f.planes.push_back(plane);
    return f;
  }();
  std::unique_ptr<ObservationBackend> backend_;
};

TEST_P(ObservationConformanceTest, StoresABatchOnceAndReportsTheDuplicate) {
  auto first = InsertOne(Batch("r1", "s1", 1));
  ASSERT_TRUE(first.ok()) << first.status().ToString();
  EXPECT_TRUE(first->stored);
  EXPECT_GT(first->observation_id, 0);
  EXPECT_TRUE(first->frame.tied);  // a map-frame session is tied by identity
  auto again = InsertOne(Batch("r1", "s1", 1));
  ASSERT_TRUE(again.ok()) << again.status().ToString();
  EXPECT_FALSE(again->stored);
  EXPECT_EQ(again->observation_id, first->observation_id);
  EXPECT_EQ(All().size(), 1u);
  auto robots = backend_->reader().ListRobots();
  ASSERT_TRUE(robots.ok());
  ASSERT_EQ(robots->size(), 1u);
  EXPECT_EQ((*robots)[0].batches, 1u);
  EXPECT_EQ((*robots)[0].features, 3u);  // two lines and a plane
}

TEST_P(ObservationConformanceTest, SameSeqInAnotherSessionOrRobotIsNewAndIdsGrow) {
  auto a = InsertOne(Batch("r1", "s1", 1));
  auto b = InsertOne(Batch("r1", "s2", 1));
  auto c = InsertOne(Batch("r2", "s1", 1));
  ASSERT_TRUE(a.ok() && b.ok() && c.ok());
  EXPECT_TRUE(a->stored && b->stored && c->stored);
  EXPECT_LT(a->observation_id, b->observation_id);
  EXPECT_LT(b->observation_id, c->observation_id);
  EXPECT_EQ(*backend_->reader().NewestObservationId(), c->observation_id);
  auto robots = backend_->reader().ListRobots();
  ASSERT_TRUE(robots.ok());
  ASSERT_EQ(robots->size(), 2u);
  EXPECT_EQ((*robots)[0].name, "r1");
  EXPECT_EQ((*robots)[0].sessions, 2u);
  EXPECT_TRUE((*robots)[0].all_sessions_tied);
  EXPECT_EQ(backend_->reader().RobotName((*robots)[1].id), "r2");
}

TEST_P(ObservationConformanceTest, RefusesAFrameKindThatDisagreesAndTheTransactionGoesOn) {
  ASSERT_TRUE(InsertOne(Batch("r1", "s1", 1)).ok());
  Status s = backend_->Write([&](ObservationWriter& w) {
    StatusOr<InsertResult> bad = w.InsertObservation(Batch("r1", "s1", 2, FrameKind::kLocal));
    EXPECT_EQ(bad.status().code(), StatusCode::kInvalidArgument);
    EXPECT_NE(bad.status().message().find("SESSION_FRAME_MAP"), std::string::npos);
    return w.InsertObservation(Batch("r1", "s1", 3)).status();
  });
  ASSERT_TRUE(s.ok()) << s.ToString();
  std::vector<StoredObservation> all = All();
  ASSERT_EQ(all.size(), 2u);
  EXPECT_EQ(all[1].seq, 3u);
}

TEST_P(ObservationConformanceTest, ARolledBackTransactionLeavesNothing) {
  Status s = backend_->Write([&](ObservationWriter& w) {
    EXPECT_TRUE(w.InsertObservation(Batch("r1", "s1", 1)).ok());
    return Status::Internal("give up");
  });
  EXPECT_EQ(s.code(), StatusCode::kInternal);
  EXPECT_TRUE(All().empty());
  EXPECT_EQ(*backend_->reader().NewestObservationId(), 0);
  EXPECT_TRUE(backend_->reader().ListRobots()->empty());
  EXPECT_FALSE(backend_->reader().FindSession("r1", "s1").ok());
  // The next transaction makes the robot and session afresh.
  auto again = InsertOne(Batch("r1", "s1", 1));
  ASSERT_TRUE(again.ok()) << again.status().ToString();
  EXPECT_TRUE(again->stored);
  EXPECT_TRUE(backend_->reader().FindSession("r1", "s1").ok());
}

TEST_P(ObservationConformanceTest, ObservationsComeBackExactlyAfterARestart) {
  std::vector<int64_t> ids;
  ASSERT_TRUE(backend_
                  ->Write([&](ObservationWriter& w) {
                    for (uint64_t seq = 1; seq <= 5; ++seq) {
                      StatusOr<InsertResult> r = w.InsertObservation(Batch("r1", "s1", seq));
                      if (!r.ok()) return r.status();
                      ids.push_back(r->observation_id);
                    }
                    return Status::Ok();
                  })
                  .ok());
  ASSERT_TRUE(backend_->Reopen().ok());
  std::vector<StoredObservation> all = All();
  ASSERT_EQ(all.size(), 5u);
  for (size_t i = 0; i < all.size(); ++i) {
    EXPECT_EQ(all[i].id, ids[i]);
    EXPECT_EQ(all[i].seq, i + 1);
    EXPECT_EQ(all[i].stamp_ns, 1001 + static_cast<int64_t>(i));
    // Bit for bit: doubles are stored exactly.
    EXPECT_EQ(all[i].features.T_frame_sensor.translation, features_.T_frame_sensor.translation);
    EXPECT_EQ(all[i].features.T_frame_sensor.rotation.coeffs(),
              features_.T_frame_sensor.rotation.coeffs());
    ASSERT_EQ(all[i].features.lines.size(), 2u);
    EXPECT_EQ(all[i].features.lines[1].b, features_.lines[1].b);
    ASSERT_EQ(all[i].features.planes.size(), 1u);
    EXPECT_EQ(all[i].features.planes[0].boundary, features_.planes[0].boundary);
  }
  EXPECT_EQ(*backend_->reader().NewestObservationId(), ids.back());
  // Ids go on growing after the restart.
  auto next = InsertOne(Batch("r1", "s1", 6));
  ASSERT_TRUE(next.ok());
  EXPECT_GT(next->observation_id, ids.back());
  // And a resend of an old batch is still a duplicate.
  auto resend = InsertOne(Batch("r1", "s1", 2));
  ASSERT_TRUE(resend.ok());
  EXPECT_FALSE(resend->stored);
  EXPECT_EQ(resend->observation_id, ids[1]);
}

TEST_P(ObservationConformanceTest, TiesAreKeptNeverMovedAndOrderedInTheCommitOrder) {
  ASSERT_TRUE(InsertOne(Batch("r1", "s1", 1)).ok());
  auto local = InsertOne(Batch("r2", "loc", 1, FrameKind::kLocal));
  auto other = InsertOne(Batch("r3", "loc", 1, FrameKind::kLocal));
  ASSERT_TRUE(local.ok() && other.ok());
  EXPECT_FALSE(local->frame.tied);
  geometry::Rigid3 T;
  T.translation = {5, -2, 0};
  T.rotation = Eigen::Quaterniond(Eigen::AngleAxisd(1.0, Eigen::Vector3d::UnitZ()));
  int64_t first_seq = 0;
  ASSERT_TRUE(backend_
                  ->Write([&](ObservationWriter& w) {
                    w.set_tie_point(other->observation_id);
                    MAPD_RETURN_IF_ERROR(w.TieSession(local->frame.session_id, T));
                    EXPECT_EQ(w.TieSession(local->frame.session_id, T).code(),
                              StatusCode::kFailedPrecondition);
                    EXPECT_TRUE(w.ties_sessions());
                    EXPECT_EQ(w.tied_session_ids(), std::vector<int64_t>{local->frame.session_id});
                    first_seq = w.tie_seq();
                    return Status::Ok();
                  })
                  .ok());
  EXPECT_GT(first_seq, 0);
  ASSERT_TRUE(backend_
                  ->Write([&](ObservationWriter& w) {
                    EXPECT_EQ(w.TieSession(local->frame.session_id, T).code(),
                              StatusCode::kFailedPrecondition);
                    MAPD_RETURN_IF_ERROR(w.TieSession(other->frame.session_id, T));
                    EXPECT_EQ(w.tie_seq(), first_seq + 1);
                    return Status::Ok();
                  })
                  .ok());
  ASSERT_TRUE(backend_->Reopen().ok());
  StatusOr<SessionFrame> f = backend_->reader().FindSession("r2", "loc");
  ASSERT_TRUE(f.ok());
  EXPECT_TRUE(f->tied);
  EXPECT_EQ(f->tie_seq, first_seq);
  EXPECT_EQ(f->tied_through_observation, other->observation_id);
  EXPECT_EQ(f->T_map_frame.translation, T.translation);
  EXPECT_EQ(backend_->reader().GetSession(f->session_id)->tie_seq, first_seq);
  EXPECT_EQ(backend_->reader().ListSessions()->size(), 3u);
  // A tie in a transaction that rolls back leaves the session untied.
  auto third = InsertOne(Batch("r4", "loc", 1, FrameKind::kLocal));
  ASSERT_TRUE(third.ok());
  (void)backend_->Write([&](ObservationWriter& w) {
    EXPECT_TRUE(w.TieSession(third->frame.session_id, T).ok());
    return Status::Internal("give up");
  });
  EXPECT_FALSE(backend_->reader().GetSession(third->frame.session_id)->tied);
}

TEST_P(ObservationConformanceTest, RangesSessionsRecentPosesAndTrails) {
  std::vector<int64_t> ids;
  ASSERT_TRUE(backend_
                  ->Write([&](ObservationWriter& w) {
                    for (uint64_t seq = 1; seq <= 10; ++seq) {
                      for (const char* robot : {"r1", "r2"}) {
                        StatusOr<InsertResult> r = w.InsertObservation(Batch(robot, "s", seq));
                        if (!r.ok()) return r.status();
                        ids.push_back(r->observation_id);
                      }
                    }
                    return Status::Ok();
                  })
                  .ok());
  std::vector<int64_t> seen;
  ASSERT_TRUE(backend_->reader()
                  .ForEachObservationBetween(ids[3], ids[7],
                                             [&](const StoredObservation& o) {
                                               seen.push_back(o.id);
                                               return Status::Ok();
                                             })
                  .ok());
  EXPECT_EQ(seen, std::vector<int64_t>(ids.begin() + 4, ids.begin() + 8));
  const int64_t r2_session = backend_->reader().FindSession("r2", "s")->session_id;
  seen.clear();
  ASSERT_TRUE(backend_->reader()
                  .ForEachObservationOfSessions({r2_session}, ids[9],
                                                [&](const StoredObservation& o) {
                                                  EXPECT_EQ(o.session_id, r2_session);
                                                  seen.push_back(o.id);
                                                  return Status::Ok();
                                                })
                  .ok());
  EXPECT_EQ(seen, (std::vector<int64_t>{ids[1], ids[3], ids[5], ids[7], ids[9]}));

  auto poses = backend_->reader().RecentPoses(r2_session, 3);
  ASSERT_TRUE(poses.ok());
  ASSERT_EQ(poses->size(), 3u);
  EXPECT_EQ((*poses)[0].seq, 10u);  // newest first
  EXPECT_EQ((*poses)[2].seq, 8u);

  auto trails = backend_->reader().ListTrails("r1", 4);
  ASSERT_TRUE(trails.ok());
  ASSERT_EQ(trails->size(), 1u);
  EXPECT_EQ((*trails)[0].robot, "r1");
  EXPECT_EQ((*trails)[0].stored, 10u);
  ASSERT_LE((*trails)[0].points.size(), 4u);
  EXPECT_EQ((*trails)[0].points.front().seq, 1u);
  EXPECT_EQ((*trails)[0].points.back().seq, 10u);
  EXPECT_EQ(backend_->reader().ListTrails("", 100)->size(), 2u);
}

// A group at once answers as one by one: new batches get ids in order,
// resends (earlier or within the group) are duplicates naming the stored
// row, and a batch refused for its frame kind leaves the others stored.
TEST_P(ObservationConformanceTest, AGroupAtOnceAnswersAsOneByOne) {
  auto first = InsertOne(Batch("r1", "s1", 1));
  ASSERT_TRUE(first.ok());
  std::vector<NewObservation> group = {Batch("r1", "s1", 2),
                                       Batch("r1", "s1", 1),
                                       Batch("r2", "s1", 1),
                                       Batch("r1", "s1", 2),
                                       Batch("r1", "s1", 3, FrameKind::kLocal),
                                       Batch("r1", "s1", 4)};
  std::vector<StatusOr<InsertResult>> results;
  Status s = backend_->Write([&](ObservationWriter& w) {
    StatusOr<std::vector<StatusOr<InsertResult>>> r = w.InsertObservations(group);
    if (!r.ok()) return r.status();
    results = *std::move(r);
    return Status::Ok();
  });
  ASSERT_TRUE(s.ok()) << s.ToString();
  ASSERT_EQ(results.size(), group.size());
  for (size_t i : {0u, 1u, 2u, 3u, 5u}) ASSERT_TRUE(results[i].ok()) << i;
  EXPECT_TRUE(results[0]->stored);
  EXPECT_EQ(results[0]->observation_id, first->observation_id + 1);
  EXPECT_FALSE(results[1]->stored);
  EXPECT_EQ(results[1]->observation_id, first->observation_id);
  EXPECT_TRUE(results[2]->stored);
  EXPECT_EQ(results[2]->observation_id, first->observation_id + 2);
  EXPECT_FALSE(results[3]->stored);
  EXPECT_EQ(results[3]->observation_id, results[0]->observation_id);
  EXPECT_EQ(results[4].status().code(), StatusCode::kInvalidArgument);
  EXPECT_TRUE(results[5]->stored);
  EXPECT_EQ(results[5]->observation_id, first->observation_id + 3);
  EXPECT_EQ(results[2]->frame.robot_id, backend_->reader().FindSession("r2", "s1")->robot_id);
  EXPECT_EQ(All().size(), 4u);
  EXPECT_EQ(*backend_->reader().NewestObservationId(), results[5]->observation_id);
  auto robots = backend_->reader().ListRobots();
  ASSERT_TRUE(robots.ok());
  EXPECT_EQ((*robots)[0].batches, 3u);  // r1: seq 1, 2, 4
  // And the next one goes on from there.
  auto next = InsertOne(Batch("r1", "s1", 5));
  ASSERT_TRUE(next.ok());
  EXPECT_EQ(next->observation_id, results[5]->observation_id + 1);
}

INSTANTIATE_TEST_SUITE_P(Backends, ObservationConformanceTest,
                         ::testing::Values("sqlite", "postgresql"),
                         [](const ::testing::TestParamInfo<std::string>& p) { return p.param; });

// --- PostgreSQL only: one database, many maps, many processes.

class PostgresMapsTest : public ::testing::Test {
 protected:
  void SetUp() override {
    cluster_ = mapd::testing::PostgresCluster::Shared();
    if (cluster_ == nullptr) GTEST_SKIP() << "no PostgreSQL (install postgresql-15)";
    conninfo_ = cluster_->NewDatabase();
  }
  mapd::testing::PostgresCluster* cluster_ = nullptr;
  std::string conninfo_;
};

TEST_F(PostgresMapsTest, MapsInOneDatabaseStayApart) {
  testing::PostgresObservationBackend site1(conninfo_, "site-1"), site2(conninfo_, "site-2");
  ASSERT_TRUE(site1.Reopen().ok());
  ASSERT_TRUE(site2.Reopen().ok());
  geometry::SensorObservation f;
  f.lines.push_back({{0, 0, 0}, {1, 0, 0}});
  NewObservation o;
  o.robot = "r1";
  o.session = "s1";
  o.seq = 1;
  o.features = &f;
  for (testing::PostgresObservationBackend* b : {&site1, &site2}) {
    Status s = b->Write([&](ObservationWriter& w) {
      StatusOr<InsertResult> r = w.InsertObservation(o);
      EXPECT_TRUE(r.ok() && r->stored) << "the same (robot, session, seq) in another map is new";
      return r.status();
    });
    ASSERT_TRUE(s.ok()) << s.ToString();
  }
  ASSERT_TRUE(site2
                  .Write([&](ObservationWriter& w) {
                    o.seq = 2;
                    return w.InsertObservation(o).status();
                  })
                  .ok());
  int n1 = 0, n2 = 0;
  ASSERT_TRUE(site1.reader()
                  .ForEachObservation([&](const StoredObservation&) {
                    ++n1;
                    return Status::Ok();
                  })
                  .ok());
  ASSERT_TRUE(site2.reader()
                  .ForEachObservation([&](const StoredObservation&) {
                    ++n2;
                    return Status::Ok();
                  })
                  .ok());
  EXPECT_EQ(n1, 1);
  EXPECT_EQ(n2, 2);
  EXPECT_EQ(site1.reader().ListRobots()->at(0).batches, 1u);
}

TEST_F(PostgresMapsTest, SeveralOpeningAnEmptyDatabaseTogetherMigrateItOnce) {
  std::vector<std::thread> threads;
  std::vector<Status> results(6);
  for (size_t i = 0; i < results.size(); ++i) {
    threads.emplace_back([&, i] {
      StatusOr<std::unique_ptr<PgObservationLog>> log =
          PgObservationLog::Open(conninfo_, "site-" + std::to_string(i));
      results[i] = log.status();
    });
  }
  for (std::thread& t : threads) t.join();
  for (const Status& s : results) EXPECT_TRUE(s.ok()) << s.ToString();
  StatusOr<PgConnection> conn = PgConnection::Connect(conninfo_);
  ASSERT_TRUE(conn.ok());
  auto rows = conn->Query("SELECT count(*) FROM mapd_schema");
  ASSERT_TRUE(rows.ok());
  EXPECT_EQ(rows->Int(0, 0), 1);
  StatusOr<PgMapCatalog> catalog = PgMapCatalog::Open(conninfo_);
  ASSERT_TRUE(catalog.ok());
  EXPECT_EQ(catalog->ListMaps()->size(), 6u);
}

TEST_F(PostgresMapsTest, OneMapdWritesAMapAtATime) {
  PgOwnership a, b;
  a.instance = {"mapd-a", "10.0.0.1:50051"};
  b.instance = {"mapd-b", "10.0.0.2:50051"};
  auto first = PgObservationLog::Open(conninfo_, "site-1", a);
  ASSERT_TRUE(first.ok()) << first.status().ToString();
  auto second = PgObservationLog::Open(conninfo_, "site-1", b);
  EXPECT_EQ(second.status().code(), StatusCode::kFailedPrecondition);
  EXPECT_THAT(second.status().message(),
              ::testing::HasSubstr("served by instance 'mapd-a' (10.0.0.1:50051, epoch 1)"));
  EXPECT_TRUE(PgObservationLog::Open(conninfo_, "site-2", b).ok()) << "other maps are free";
  first->reset();  // closing lets its lease lapse
  auto taken = PgObservationLog::Open(conninfo_, "site-1", b);
  ASSERT_TRUE(taken.ok()) << taken.status().ToString();
  EXPECT_EQ((*taken)->lease().epoch, 2);
}

// Map ids up to mapd's 128 characters, longer than a PostgreSQL identifier:
// partitions are named by number, so two long ids never share one.
TEST_F(PostgresMapsTest, LongMapIdsStayApart) {
  const std::string a = std::string(127, 'x') + "a", b = std::string(127, 'x') + "b";
  testing::PostgresObservationBackend site_a(conninfo_, a), site_b(conninfo_, b);
  ASSERT_TRUE(site_a.Reopen().ok());
  ASSERT_TRUE(site_b.Reopen().ok());
  geometry::SensorObservation f;
  NewObservation o;
  o.robot = "r1";
  o.session = "s1";
  o.seq = 1;
  o.features = &f;
  ASSERT_TRUE(
      site_a.Write([&](ObservationWriter& w) { return w.InsertObservation(o).status(); }).ok());
  int n = 0;
  ASSERT_TRUE(site_b.reader()
                  .ForEachObservation([&](const StoredObservation&) {
                    ++n;
                    return Status::Ok();
                  })
                  .ok());
  EXPECT_EQ(n, 0);
  EXPECT_EQ(PgObservationLog::Open(conninfo_, std::string(129, 'x')).status().code(),
            StatusCode::kInvalidArgument);
  EXPECT_EQ(PgObservationLog::Open(conninfo_, ".hidden").status().code(),
            StatusCode::kInvalidArgument);
}

TEST_F(PostgresMapsTest, TheCatalogListsMapsAndKeepsTheirSettings) {
  StatusOr<PgMapCatalog> catalog = PgMapCatalog::Open(conninfo_);
  ASSERT_TRUE(catalog.ok()) << catalog.status().ToString();
  EXPECT_TRUE(catalog->ListMaps()->empty());
  ASSERT_TRUE(catalog->CreateMap("site-7", "fusion.eta_m = 0.2\n", 1).ok());
  EXPECT_EQ(catalog->CreateMap("site-7", "", 2).code(), StatusCode::kAlreadyExists);
  EXPECT_EQ(catalog->CreateMap("a b", "", 2).code(), StatusCode::kInvalidArgument);
  ASSERT_TRUE(PgObservationLog::Open(conninfo_, "default").ok());  // opening adds its row
  EXPECT_EQ(*catalog->ListMaps(), (std::vector<std::string>{"default", "site-7"}));
  EXPECT_EQ(*catalog->Settings("site-7"), "fusion.eta_m = 0.2\n");
  EXPECT_EQ(*catalog->Settings("default"), "");
  EXPECT_EQ(catalog->Settings("site-8").status().code(), StatusCode::kNotFound);
}

// mapd migrate's map: in the catalog while it is copied, but neither listed
// nor served; a copier that died leaves a part that the next one discards.
TEST_F(PostgresMapsTest, AnImportingMapIsHiddenUntilFinishedAndADeadOneIsDiscarded) {
  StatusOr<PgMapCatalog> catalog = PgMapCatalog::Open(conninfo_);
  ASSERT_TRUE(catalog.ok()) << catalog.status().ToString();
  const PgInstance first{"migrate-1", ""}, second{"migrate-2", ""};
  bool restarted = true;
  ASSERT_TRUE(
      catalog->BeginImport("site-1", "fusion.eta_m = 0.2\n", 1, first, 0.5, &restarted).ok());
  EXPECT_FALSE(restarted);
  EXPECT_TRUE(catalog->ListMaps()->empty());
  EXPECT_EQ(catalog->Settings("site-1").status().code(), StatusCode::kNotFound);
  // The importer writes under its lease; another one is refused meanwhile.
  const auto open = [&](const PgInstance& as) {
    PgOwnership own;
    own.instance = as;
    StatusOr<std::unique_ptr<PgStore>> store =
        PgStore::Open(conninfo_, "site-1", StoreOptions{}, own);
    EXPECT_TRUE(store.ok()) << store.status().ToString();
    return store.ok() ? std::move(store).value() : nullptr;
  };
  std::unique_ptr<PgStore> part = open(first);
  ASSERT_NE(part, nullptr);
  {
    geometry::SensorObservation features;
    NewObservation o;
    o.robot = "r1";
    o.session = "s1";
    o.seq = 1;
    o.features = &features;
    auto txn = part->BeginWrite();
    ASSERT_TRUE(txn.ok());
    ASSERT_TRUE((*txn)->InsertObservation(o).ok());
    ASSERT_TRUE((*txn)->Commit().ok());
  }
  Status busy = catalog->BeginImport("site-1", "", 2, second, 5, &restarted);
  EXPECT_EQ(busy.code(), StatusCode::kFailedPrecondition) << busy.ToString();
  EXPECT_THAT(busy.message(), ::testing::HasSubstr("migrate-1"));
  // The first importer is gone (its lease lapsed): the next one starts over.
  part.reset();
  ASSERT_TRUE(catalog->BeginImport("site-1", "", 3, second, 5, &restarted).ok());
  EXPECT_TRUE(restarted);
  MapLease dead;
  dead.map_id = "site-1";
  dead.owner = first.name;
  dead.epoch = 1;
  part = open(second);
  ASSERT_NE(part, nullptr);
  EXPECT_EQ(*part->NewestObservationId(), 0) << "the dead import's rows are gone";
  EXPECT_EQ(catalog->FinishImport(dead).code(), StatusCode::kFailedPrecondition)
      << "a copier that woke up late cannot publish the new import";
  EXPECT_TRUE(catalog->ListMaps()->empty());
  ASSERT_TRUE(catalog->FinishImport(part->lease()).ok());
  part.reset();
  EXPECT_EQ(*catalog->ListMaps(), std::vector<std::string>{"site-1"});
  EXPECT_EQ(*catalog->Settings("site-1"), "");
  EXPECT_EQ(catalog->BeginImport("site-1", "", 4, first, 5, &restarted).code(),
            StatusCode::kAlreadyExists);
  EXPECT_EQ(catalog->DiscardImport("site-1").code(), StatusCode::kFailedPrecondition);
  EXPECT_EQ(*catalog->ListMaps(), std::vector<std::string>{"site-1"});
}

// DeleteMap's archive: the map's rows stay, nobody lists, serves or takes
// it, its old owner is fenced off, and it comes back as it was; a purge
// deletes it for good.
TEST_F(PostgresMapsTest, AnArchivedMapIsFencedHiddenAndRestoredAsItWas) {
  StatusOr<PgMapCatalog> catalog = PgMapCatalog::Open(conninfo_);
  ASSERT_TRUE(catalog.ok()) << catalog.status().ToString();
  ASSERT_TRUE(catalog->CreateMap("site-1", "fusion.eta_m = 0.2\n", 1).ok());
  const auto open = [&](const std::string& name) -> StatusOr<std::unique_ptr<PgStore>> {
    PgOwnership own;
    own.instance = PgInstance{name, "10.0.0.1:50051"};
    own.lease_ttl_s = 30;
    return PgStore::Open(conninfo_, "site-1", StoreOptions{}, own);
  };
  const auto insert = [](PgStore& store, uint64_t seq) {
    geometry::SensorObservation features;
    NewObservation o;
    o.robot = "r1";
    o.session = "s1";
    o.seq = seq;
    o.features = &features;
    auto txn = store.BeginWrite();
    if (!txn.ok()) return txn.status();
    MAPD_RETURN_IF_ERROR((*txn)->InsertObservation(o).status());
    return (*txn)->Commit();
  };
  StatusOr<std::unique_ptr<PgStore>> owner = open("mapd-a");
  ASSERT_TRUE(owner.ok()) << owner.status().ToString();
  ASSERT_TRUE(insert(**owner, 1).ok());

  ASSERT_TRUE(catalog->ArchiveMap((*owner)->lease(), 42).ok());
  EXPECT_TRUE(catalog->ListMaps()->empty());
  EXPECT_EQ(catalog->Settings("site-1").status().code(), StatusCode::kNotFound);
  ASSERT_EQ(catalog->ListArchived()->size(), 1u);
  EXPECT_EQ((*catalog->ListArchived())[0].id, "site-1");
  EXPECT_EQ((*catalog->ListArchived())[0].archived_ns, 42);
  // The old owner can no longer write; no instance can take the map.
  EXPECT_FALSE(insert(**owner, 2).ok());
  StatusOr<std::unique_ptr<PgStore>> taker = open("mapd-b");
  EXPECT_EQ(taker.status().code(), StatusCode::kFailedPrecondition);
  EXPECT_EQ(catalog->ArchiveMap((*owner)->lease(), 43).code(), StatusCode::kFailedPrecondition);
  EXPECT_EQ(catalog->CreateMap("site-1", "", 2).code(), StatusCode::kAlreadyExists);
  owner->reset();

  EXPECT_EQ(catalog->RestoreMap("site-2").code(), StatusCode::kNotFound);
  ASSERT_TRUE(catalog->RestoreMap("site-1").ok());
  EXPECT_EQ(catalog->RestoreMap("site-1").code(), StatusCode::kFailedPrecondition);
  EXPECT_EQ(*catalog->ListMaps(), std::vector<std::string>{"site-1"});
  EXPECT_EQ(*catalog->Settings("site-1"), "fusion.eta_m = 0.2\n");
  EXPECT_TRUE(catalog->ListArchived()->empty());
  taker = open("mapd-b");
  ASSERT_TRUE(taker.ok()) << taker.status().ToString();
  EXPECT_EQ(*(*taker)->NewestObservationId(), 1) << "its rows are as they were";
  EXPECT_EQ(catalog->PurgeArchived("site-1").code(), StatusCode::kFailedPrecondition)
      << "only an archived map is purged";

  ASSERT_TRUE(catalog->ArchiveMap((*taker)->lease(), 44).ok());
  taker->reset();
  ASSERT_TRUE(catalog->PurgeArchived("site-1").ok());
  EXPECT_EQ(catalog->PurgeArchived("site-1").code(), StatusCode::kNotFound);
  EXPECT_TRUE(catalog->ListArchived()->empty());
  ASSERT_TRUE(catalog->CreateMap("site-1", "", 5).ok()) << "its id is free again";
  taker = open("mapd-b");
  ASSERT_TRUE(taker.ok()) << taker.status().ToString();
  EXPECT_EQ(*(*taker)->NewestObservationId(), 0) << "a new, empty map";
}

TEST_F(PostgresMapsTest, ABadMapIdOrServerIsAClearError) {
  auto bad = PgObservationLog::Open(conninfo_, "site 7; DROP TABLE robots");
  EXPECT_EQ(bad.status().code(), StatusCode::kInvalidArgument);
  EXPECT_NE(bad.status().message().find("not a map id"), std::string::npos);
  auto nobody = PgObservationLog::Open("host=/nonexistent port=1 user=mapd dbname=x", "site-1");
  EXPECT_EQ(nobody.status().code(), StatusCode::kUnavailable);
  EXPECT_NE(nobody.status().message().find("cannot connect to PostgreSQL"), std::string::npos);
}

}  // namespace
}  // namespace mapd::storage
