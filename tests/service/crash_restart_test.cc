// The durability contract with the real binary: robots stream, mapd is killed
// with SIGKILL mid-stream, restarted on the same database; every batch that
// was acknowledged is there, and the served map is exactly a recomputation
// from the stored raw observations: by a fresh engine fed as mapd feeds its
// own (a deterministic restart), and by the independent batch reference
// (tests/fusion/batch_reference.h: a correct one).
#include <grpcpp/grpcpp.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <map>
#include <mutex>
#include <random>
#include <set>
#include <thread>

#include "common/batches.h"
#include "common/process.h"
#include "common/temp_dir.h"
#include "fusion/batch_reference.h"
#include "fusion/engine.h"
#include "fusion/projection.h"
#include "mapserver/v1/map_service.grpc.pb.h"
#include "service/ingest_batch.h"
#include "storage/sqlite/store.h"
#include "storage/store.h"

namespace mapd::testing {
namespace {

namespace pb = mapserver::v1;

constexpr int kRobots = 4;
constexpr int kBatchesPerRobot = 400;

std::vector<pb::ObservationBatch> RobotBatches(int robot) {
  std::mt19937_64 rng(static_cast<uint64_t>(robot) + 1);
  std::uniform_real_distribution<double> x(1, 9), y(1, 7), yaw(-3, 3);
  std::vector<pb::ObservationBatch> out;
  for (int i = 1; i <= kBatchesPerRobot; ++i) {
    out.push_back(RoomBatch("robot" + std::to_string(robot), "s1", static_cast<uint64_t>(i), x(rng),
                            y(rng), yaw(rng), &rng));
  }
  return out;
}

struct StreamResult {
  std::set<uint64_t> stored;     // seqs acknowledged STORED
  std::set<uint64_t> duplicate;  // seqs acknowledged DUPLICATE
  int rejected = 0;
};

// Streams all batches (pipelined) and collects acks until the stream ends.
StreamResult Stream(const std::string& address, const std::vector<pb::ObservationBatch>& batches,
                    std::atomic<int>* acked_total = nullptr) {
  auto stub =
      pb::MapService::NewStub(grpc::CreateChannel(address, grpc::InsecureChannelCredentials()));
  grpc::ClientContext ctx;
  auto stream = stub->Ingest(&ctx);
  StreamResult result;
  std::thread reader([&] {
    pb::IngestAck ack;
    while (stream->Read(&ack)) {
      if (ack.result() == pb::IngestAck::STORED)
        result.stored.insert(ack.seq());
      else if (ack.result() == pb::IngestAck::DUPLICATE)
        result.duplicate.insert(ack.seq());
      else
        ++result.rejected;
      if (acked_total) ++*acked_total;
    }
  });
  for (const auto& b : batches) {
    if (!stream->Write(b)) break;
    if (acked_total)
      std::this_thread::sleep_for(std::chrono::microseconds(200));  // keep it mid-stream
  }
  stream->WritesDone();
  reader.join();
  stream->Finish();
  return result;
}

// The map once the fuser has caught up with every acknowledged batch (a query
// waits for it only up to a bound, which a sanitizer build on a busy machine exceeds).
std::vector<pb::FusedFeature> FetchMap(const std::string& address) {
  auto stub =
      pb::MapService::NewStub(grpc::CreateChannel(address, grpc::InsecureChannelCredentials()));
  for (int i = 0; i < 1200; ++i) {
    grpc::ClientContext stats_ctx;
    pb::Stats stats;
    if (stub->GetStats(&stats_ctx, {}, &stats).ok() && stats.fusion_backlog() == 0) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  grpc::ClientContext ctx;
  auto reader = stub->GetFeatureMap(&ctx, {});
  std::vector<pb::FusedFeature> out;
  pb::FeatureMapPage page;
  while (reader->Read(&page)) out.insert(out.end(), page.features().begin(), page.features().end());
  EXPECT_TRUE(reader->Finish().ok());
  return out;
}

TEST(CrashRestartTest, AcknowledgedBatchesSurviveSigkillAndTheMapEqualsABatchRecomputation) {
  TempDir dir;
  const std::string db = dir.File("map.db");
  std::vector<std::vector<pb::ObservationBatch>> batches;
  for (int r = 0; r < kRobots; ++r) batches.push_back(RobotBatches(r));

  // 1. Stream from all robots; SIGKILL the server once a third is acknowledged.
  //    A fusion snapshot every 5 observations: the kill likely lands in or
  //    between snapshot writes, and the restart must still be exact.
  const std::vector<std::string> args = {"--snapshot.every_observations", "5"};
  MapdProcess mapd = StartMapd(db, args);
  ASSERT_GT(mapd.port, 0) << mapd.log();
  std::atomic<int> acked{0};
  std::vector<StreamResult> first(kRobots);
  std::vector<std::thread> robots;
  for (int r = 0; r < kRobots; ++r) {
    robots.emplace_back([&, r] {
      first[static_cast<size_t>(r)] = Stream(mapd.address, batches[static_cast<size_t>(r)], &acked);
    });
  }
  while (acked < kRobots * kBatchesPerRobot / 3)
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  EXPECT_EQ(Stop(mapd.pid, SIGKILL), 128 + SIGKILL);
  for (auto& t : robots) t.join();
  size_t acked_stored = 0;
  for (const auto& f : first) acked_stored += f.stored.size();
  ASSERT_LT(acked_stored, static_cast<size_t>(kRobots * kBatchesPerRobot))
      << "the kill came too late";

  // 2. Restart on the same database and resend everything, as robots do.
  //    A snapshot written before the kill is used (a slow build may not have
  //    written one yet: then the restart replays everything).
  const bool snapshot_written = mapd.log().find("event=snapshot_written") != std::string::npos;
  mapd = StartMapd(db, args);
  ASSERT_GT(mapd.port, 0) << mapd.log();
  if (snapshot_written) {
    // Serving before the replay ends: the recovery's last line may come later.
    EXPECT_NE(mapd.log().find("event=serving_while_replaying from=snapshot"), std::string::npos)
        << mapd.log();
  }
  for (int r = 0; r < kRobots; ++r) {
    const StreamResult again = Stream(mapd.address, batches[static_cast<size_t>(r)]);
    EXPECT_EQ(again.rejected, 0);
    EXPECT_EQ(again.stored.size() + again.duplicate.size(), static_cast<size_t>(kBatchesPerRobot));
    // Every batch acknowledged before the crash is there: resending it is a duplicate.
    for (uint64_t seq : first[static_cast<size_t>(r)].stored) {
      EXPECT_EQ(again.duplicate.count(seq), 1u) << "robot" << r << " seq " << seq << " was lost";
    }
  }
  const std::vector<pb::FusedFeature> served = FetchMap(mapd.address);
  ASSERT_FALSE(served.empty());
  EXPECT_EQ(Stop(mapd.pid, SIGTERM), 0) << mapd.log();

  // 3. Recompute the map from the raw observations in the database, in
  //    commit (= id) order, the order mapd fused them in (the default bounded
  //    engine is deterministic but not order independent), and compare.
  //    Fed as mapd's fuser feeds it (MapCore::Fuse): with the sensor origin.
  auto store = storage::SqliteStore::Open(db, {});
  ASSERT_TRUE(store.ok()) << store.status().ToString();
  std::vector<storage::StoredObservation> observations;
  ASSERT_TRUE((*store)
                  ->ForEachObservation([&](const storage::StoredObservation& o) {
                    observations.push_back(o);
                    return Status::Ok();
                  })
                  .ok());
  EXPECT_EQ(observations.size(), static_cast<size_t>(kRobots * kBatchesPerRobot));
  fusion::FusionEngine engine{fusion::FusionParams{}};
  std::vector<fusion::testing::BatchObservation> batch;  // the same input, for the reference
  for (const auto& o : observations) {
    auto projected = fusion::ProjectToGround(
        o.features, geometry::Rigid3::Identity(),
        static_cast<fusion::FeatureId>(o.id) << service::kFeatureIdBits, engine.params());
    ASSERT_TRUE(projected.ok());
    ASSERT_TRUE(engine
                    .AddFrom(static_cast<fusion::ObservationId>(o.id),
                             static_cast<fusion::RobotId>(o.robot_id), projected->sensor_xy_m,
                             projected->ground)
                    .ok());
    batch.push_back({static_cast<fusion::ObservationId>(o.id),
                     static_cast<fusion::RobotId>(o.robot_id), projected->ground,
                     /*has_sensor=*/true, projected->sensor_xy_m});
  }
  const std::vector<fusion::FusedFeature> expected = engine.Published();
  ASSERT_EQ(served.size(), expected.size());
  for (size_t i = 0; i < expected.size(); ++i) {
    EXPECT_EQ(served[i].id(), expected[i].id);
    EXPECT_EQ(served[i].support(), expected[i].support);
    EXPECT_NEAR(served[i].a().x(), expected[i].segment.a.x(), 1e-9);
    EXPECT_NEAR(served[i].a().y(), expected[i].segment.a.y(), 1e-9);
    EXPECT_NEAR(served[i].b().x(), expected[i].segment.b.x(), 1e-9);
    EXPECT_NEAR(served[i].b().y(), expected[i].segment.b.y(), 1e-9);
  }

  // 4. The independent batch reference on the same stored observations, with
  //    the server's parameters. It models exact mode; the server runs the
  //    default bounded mode, whose promise (docs/algorithms.md A.5;
  //    tests/fusion/property_test.cc, "Bounded mode") is the reference's map
  //    wherever folding dropped no link that mattered, with support past 32
  //    never below the reference's. Here every view covers 80-95 % of its wall
  //    and links to every other view of it, so no link hangs on one feature:
  //    the served map must be the reference's.
  const fusion::testing::BatchResult reference = fusion::testing::BatchFuse(batch, engine.params());
  ASSERT_TRUE(reference.evidence.on) << "mapd feeds sensor origins: the reference must model them";
  ASSERT_EQ(reference.walls.size(), 4u) << "the room has four walls";
  ASSERT_EQ(served.size(), reference.walls.size());
  for (size_t i = 0; i < reference.walls.size(); ++i) {
    const fusion::testing::BatchCluster& wall = reference.walls[i];
    EXPECT_EQ(served[i].id(), wall.id);
    EXPECT_EQ(served[i].member_count(), wall.members.size()) << wall.id;
    EXPECT_EQ(wall.support, static_cast<uint32_t>(kRobots * kBatchesPerRobot)) << wall.id;
    EXPECT_GE(served[i].support(), wall.support) << wall.id;  // bounded: may overcount past 32
    // The same endpoints (the reference does not orient its segments).
    const geometry::Vec2 a(served[i].a().x(), served[i].a().y());
    const geometry::Vec2 b(served[i].b().x(), served[i].b().y());
    const double apart_m =
        std::min(std::max((a - wall.segment.a).norm(), (b - wall.segment.b).norm()),
                 std::max((a - wall.segment.b).norm(), (b - wall.segment.a).norm()));
    // Settled walls (docs/algorithms.md A.5) keep a fit within the refit
    // tolerance of the exact one; corners may move by a little more.
    EXPECT_LE(apart_m, 1e-9 + 2.0 * engine.params().refit_tolerance_m) << wall.id;
  }

  // The persisted fused table agrees with the served map too.
  auto rows = (*store)->LoadFused();
  ASSERT_TRUE(rows.ok());
  ASSERT_EQ(rows->size(), served.size());
  for (size_t i = 0; i < served.size(); ++i) {
    EXPECT_EQ((*rows)[i].id, served[i].id());
    EXPECT_NEAR((*rows)[i].segment.a.x(), served[i].a().x(), 1e-9);
  }
}

}  // namespace
}  // namespace mapd::testing
