// Storage faults as an operator meets them, on a real file system: a disk
// that fills up (a tmpfs of a few MiB), a read-only mount, another
// application's database. mapd must answer each honestly: refuse to start
// with the reason, or report NOT_SERVING with the reason while it cannot
// write, refuse batches without losing an acknowledged one, recover by itself
// when space comes back, and stop within its bound whatever the disk does.
// The tmpfs tests need root (a private mount namespace); they skip without it.
#include <gmock/gmock.h>
#include <grpcpp/grpcpp.h>
#include <gtest/gtest.h>
#include <sqlite3.h>

#include <set>
#include <thread>

#include "common/batches.h"
#include "common/health.h"
#include "common/private_tmpfs.h"
#include "common/process.h"
#include "common/temp_dir.h"
#include "mapserver/v1/map_service.grpc.pb.h"

namespace mapd::testing {
namespace {

namespace pb = mapserver::v1;
using ::testing::HasSubstr;

// Streams batches of robot r1 until one is rejected or `count` are sent;
// returns the seqs acknowledged STORED, and the first rejection's message.
std::set<uint64_t> StreamUntilRefused(const std::string& address, uint64_t first_seq,
                                      uint64_t count, std::string* refusal) {
  auto stub =
      pb::MapService::NewStub(grpc::CreateChannel(address, grpc::InsecureChannelCredentials()));
  grpc::ClientContext ctx;
  ctx.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(60));
  auto stream = stub->Ingest(&ctx);
  std::mt19937_64 rng(first_seq);
  std::set<uint64_t> stored;
  for (uint64_t seq = first_seq; seq < first_seq + count; ++seq) {
    // One at a time: the first refusal ends the run.
    if (!stream->Write(RoomBatch("r1", "s1", seq, 5, 4, 0.001 * static_cast<double>(seq), &rng)))
      break;
    pb::IngestAck ack;
    if (!stream->Read(&ack)) break;
    if (ack.result() == pb::IngestAck::STORED) stored.insert(ack.seq());
    if (ack.result() == pb::IngestAck::REJECTED) {
      *refusal = ack.message();
      EXPECT_EQ(ack.code(), grpc::StatusCode::UNAVAILABLE) << ack.message();
      break;
    }
  }
  stream->WritesDone();
  stream->Finish();
  return stored;
}

pb::Stats GetStats(const std::string& address) {
  auto stub =
      pb::MapService::NewStub(grpc::CreateChannel(address, grpc::InsecureChannelCredentials()));
  grpc::ClientContext ctx;
  ctx.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(10));
  pb::Stats stats;
  EXPECT_TRUE(stub->GetStats(&ctx, {}, &stats).ok());
  return stats;
}

bool WaitForHealth(const std::string& address, Health want, std::chrono::seconds timeout) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  while (std::chrono::steady_clock::now() < deadline) {
    if (CheckHealth(address) == want) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  return false;
}

TEST(MapdFaultsTest, AFullDiskIsNotServingThenServesAgainAndLosesNothing) {
  TempDir dir;
  PrivateTmpfs fs(dir.File("fs"), 2 << 20);
  if (!fs.available()) GTEST_SKIP() << fs.error();
  MapdProcess mapd =
      StartMapd(fs.File("map.db"), {"--snapshot.every_observations", "0"}, MAPD_BINARY,
                std::chrono::seconds(20), "serving", dir.File("mapd.log"));
  ASSERT_GT(mapd.port, 0) << mapd.log();

  std::string refusal;
  std::set<uint64_t> stored = StreamUntilRefused(mapd.address, 1, 100000, &refusal);
  ASSERT_FALSE(refusal.empty()) << "2 MiB never filled up";
  EXPECT_GT(stored.size(), 10u);
  EXPECT_THAT(refusal, HasSubstr("full"));
  ASSERT_TRUE(WaitForHealth(mapd.address, Health::kNotServing, std::chrono::seconds(10)))
      << mapd.log();
  EXPECT_THAT(GetStats(mapd.address).write_failure(), HasSubstr("full"));
  EXPECT_THAT(mapd.log(), HasSubstr("event=not_writable"));
  // Refused while the disk is full (at once, or, if a probe found a little
  // room meanwhile, by the failed commit), nothing stored.
  std::string again;
  EXPECT_TRUE(StreamUntilRefused(mapd.address, 100000, 5, &again).empty());
  EXPECT_THAT(
      again, ::testing::AnyOf(HasSubstr("does not take writes"), HasSubstr("could not be stored")));

  // Space comes back: mapd's probe notices by itself.
  ASSERT_TRUE(fs.Resize(64 << 20));
  ASSERT_TRUE(WaitForHealth(mapd.address, Health::kServing, std::chrono::seconds(20)))
      << mapd.log();
  EXPECT_THAT(mapd.log(), HasSubstr("event=writable_again"));
  std::string none;
  const std::set<uint64_t> later = StreamUntilRefused(mapd.address, 200000, 20, &none);
  EXPECT_TRUE(none.empty()) << none;
  EXPECT_EQ(later.size(), 20u);
  EXPECT_EQ(Stop(mapd.pid, SIGTERM), 0) << mapd.log();

  mapd = StartMapd(fs.File("map.db"), {}, MAPD_BINARY, std::chrono::seconds(20), "serving",
                   dir.File("mapd2.log"));
  ASSERT_GT(mapd.port, 0) << mapd.log();
  EXPECT_EQ(GetStats(mapd.address).batches(), stored.size() + later.size());
  EXPECT_EQ(Stop(mapd.pid, SIGTERM), 0);
}

TEST(MapdFaultsTest, SigtermWithTheDiskFullExitsWithinItsBound) {
  TempDir dir;
  PrivateTmpfs fs(dir.File("fs"), 2 << 20);
  if (!fs.available()) GTEST_SKIP() << fs.error();
  MapdProcess mapd = StartMapd(
      fs.File("map.db"),
      {"--shutdown_grace_s", "1", "--shutdown_flush_s", "2", "--snapshot.every_observations", "0"},
      MAPD_BINARY, std::chrono::seconds(20), "serving", dir.File("mapd.log"));
  ASSERT_GT(mapd.port, 0) << mapd.log();
  std::string refusal;
  StreamUntilRefused(mapd.address, 1, 100000, &refusal);
  ASSERT_FALSE(refusal.empty());
  // Before the fix the writer retried forever and SIGTERM never finished;
  // Stop() kills it after 20 s, which would show here as 137.
  EXPECT_EQ(Stop(mapd.pid, SIGTERM), 0) << mapd.log();
  EXPECT_THAT(mapd.log(), HasSubstr("event=stopped"));
}

TEST(MapdFaultsTest, AReadOnlyDatabaseIsRefusedAtStartWithTheReason) {
  TempDir dir;
  PrivateTmpfs fs(dir.File("fs"), 8 << 20);
  if (!fs.available()) GTEST_SKIP() << fs.error();
  MapdProcess mapd = StartMapd(fs.File("map.db"), {}, MAPD_BINARY, std::chrono::seconds(20),
                               "serving", dir.File("mapd.log"));
  ASSERT_GT(mapd.port, 0) << mapd.log();
  EXPECT_EQ(Stop(mapd.pid, SIGTERM), 0);
  ASSERT_TRUE(fs.SetReadOnly());
  const CommandResult r =
      RunCommand({MAPD_BINARY, "--db", fs.File("map.db"), "--listen", "127.0.0.1:0"});
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_THAT(r.err, HasSubstr("read-only"));
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
}

TEST(MapdFaultsTest, AnotherApplicationsDatabaseIsRefusedAndLeftAlone) {
  TempDir dir;
  sqlite3* db = nullptr;
  ASSERT_EQ(sqlite3_open(dir.File("inventory.db").c_str(), &db), SQLITE_OK);
  ASSERT_EQ(sqlite3_exec(db, "CREATE TABLE parts (id INTEGER PRIMARY KEY, name TEXT)", nullptr,
                         nullptr, nullptr),
            SQLITE_OK);
  sqlite3_close(db);
  const CommandResult r =
      RunCommand({MAPD_BINARY, "--db", dir.File("inventory.db"), "--listen", "127.0.0.1:0"});
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_THAT(r.err, HasSubstr("is not a mapd database"));
  EXPECT_THAT(r.err, HasSubstr("parts"));
  ASSERT_EQ(sqlite3_open(dir.File("inventory.db").c_str(), &db), SQLITE_OK);
  sqlite3_stmt* q = nullptr;
  ASSERT_EQ(sqlite3_prepare_v2(db, "SELECT count(*) FROM sqlite_master", -1, &q, nullptr),
            SQLITE_OK);
  ASSERT_EQ(sqlite3_step(q), SQLITE_ROW);
  EXPECT_EQ(sqlite3_column_int(q, 0), 1);
  sqlite3_finalize(q);
  sqlite3_close(db);
}

}  // namespace
}  // namespace mapd::testing
