// The mapd binary as an operator meets it: bad flags, a damaged database,
// SIGTERM with robots still streaming.
#include <gmock/gmock.h>
#include <grpcpp/grpcpp.h>
#include <gtest/gtest.h>

#include <atomic>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <thread>

#include "common/batches.h"
#include "common/health.h"
#include "common/process.h"
#include "common/temp_dir.h"
#include "mapserver/v1/map_service.grpc.pb.h"
#include "service/config.h"

namespace mapd::testing {
namespace {

namespace pb = mapserver::v1;
using ::testing::HasSubstr;

TEST(MapdProcessTest, ABadFlagExitsTwoNamingTheSetting) {
  TempDir dir;
  const CommandResult r =
      RunCommand({MAPD_BINARY, "--db", dir.File("m.db"), "--fusion.gamma", "7"});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.err, HasSubstr("gamma"));
}

TEST(MapdProcessTest, HelpListsTheSettings) {
  const CommandResult r = RunCommand({MAPD_BINARY, "--help"});
  EXPECT_EQ(r.exit_code, 0);
  EXPECT_THAT(r.out, HasSubstr("--fusion.eta_m"));
  EXPECT_THAT(r.out, HasSubstr("--sync"));
}

TEST(MapdProcessTest, HelpShowsTheDefaultsOfServerConfig) {
  const CommandResult r = RunCommand({MAPD_BINARY, "--help"});
  const service::ServerConfig defaults;
  EXPECT_THAT(r.out, HasSubstr("--listen <text>=" + defaults.listen));
  EXPECT_THAT(r.out, HasSubstr("token"));  // the offline token subcommand
}

TEST(MapdProcessTest, UnknownFlagsAndValuesAreNamedAndLaterFlagsWin) {
  CommandResult r = RunCommand({MAPD_BINARY, "--no-such-setting", "1"});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.err, HasSubstr("--no-such-setting"));
  // The container entrypoint passes defaults first and the user's flags after them.
  r = RunCommand({MAPD_BINARY, "--fusion.gamma", "0.3", "--fusion.gamma=0.5", "--print-config"});
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_THAT(r.out, HasSubstr("fusion.gamma = 0.5"));
  TempDir dir;
  r = RunCommand(
      {MAPD_BINARY, "token", "create", "--db", dir.File("t.db"), "--role", "boss", "--name", "x"});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.err, HasSubstr("--role"));
  r = RunCommand({MAPD_BINARY, "token", "revoke", "--db", dir.File("t.db"), "--id", "0"});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.err, HasSubstr("--id"));
}

TEST(MapdProcessTest, VersionPrintsTheProjectVersion) {
  const CommandResult r = RunCommand({MAPD_BINARY, "--version"});
  EXPECT_EQ(r.exit_code, 0);
  EXPECT_EQ(r.out, std::string("mapd ") + MAPD_PROJECT_VERSION + "\n");
}

// The container HEALTHCHECK's probe: 0 while mapd serves, 3 once it is gone.
TEST(MapdProcessTest, HealthProbeSaysServingThenUnreachable) {
  TempDir dir;
  MapdProcess mapd = StartMapd(dir.File("map.db"));
  ASSERT_GT(mapd.port, 0) << mapd.log();
  CommandResult r = RunCommand({MAPD_HEALTH_BINARY, "--server", mapd.address});
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_THAT(r.out, HasSubstr("SERVING"));
  // One map's health: the default map is served, another is not known.
  r = RunCommand({MAPD_HEALTH_BINARY, "--server", mapd.address, "--map", "default"});
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_THAT(r.out, HasSubstr("map default SERVING"));
  r = RunCommand({MAPD_HEALTH_BINARY, "--server", mapd.address, "--map", "site-9"});
  EXPECT_EQ(r.exit_code, 3);
  EXPECT_THAT(r.err, HasSubstr("code 5"));  // NOT_FOUND
  ASSERT_EQ(Stop(mapd.pid, SIGTERM), 0);
  r = RunCommand({MAPD_HEALTH_BINARY, "--server", mapd.address, "--timeout", "2"});
  EXPECT_EQ(r.exit_code, 3);
  EXPECT_EQ(RunCommand({MAPD_HEALTH_BINARY, "--bogus", "x"}).exit_code, 2);
}

// glibc reads GLIBC_TUNABLES at process start, so mapd can only say whether
// its malloc uses huge pages, and what to set when it does not.
TEST(MapdProcessTest, TheStartLogSaysWhetherMallocUsesHugePages) {
  const char* saved = std::getenv("GLIBC_TUNABLES");
  const std::string before = saved == nullptr ? "" : saved;
  const auto start_log = [](const std::string& tunables) {
    TempDir dir;
    setenv("GLIBC_TUNABLES", tunables.c_str(), 1);
    MapdProcess mapd = StartMapd(dir.File("map.db"), {}, kDefaultMapdBinary,
                                 std::chrono::seconds(20), "listening");
    std::string log = mapd.log();
    if (mapd.pid > 0) Stop(mapd.pid, SIGTERM);
    return log;
  };
  EXPECT_THAT(start_log("glibc.malloc.hugetlb=1"), HasSubstr("malloc_huge_pages=on"));
  EXPECT_THAT(start_log("glibc.malloc.check=0:glibc.malloc.hugetlb=2"),
              HasSubstr("malloc_huge_pages=on"));
  const std::string off = start_log("glibc.malloc.hugetlb=0");
  EXPECT_THAT(off, HasSubstr("malloc_huge_pages=\"off"));
  EXPECT_THAT(off, HasSubstr("GLIBC_TUNABLES=glibc.malloc.hugetlb=1"));
  EXPECT_THAT(start_log("xglibc.malloc.hugetlb=1"), HasSubstr("malloc_huge_pages=\"off"));
  if (saved == nullptr) {
    unsetenv("GLIBC_TUNABLES");
  } else {
    setenv("GLIBC_TUNABLES", before.c_str(), 1);
  }
}

// A typo in --db once made the directories and a new, empty map there.
TEST(MapdProcessTest, ADatabaseInADirectoryThatDoesNotExistIsRefused) {
  TempDir dir;
  const std::string db = dir.File("no/such/dir/map.db");
  const CommandResult r = RunCommand({MAPD_BINARY, "--db", db, "--listen", "127.0.0.1:0"});
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_THAT(r.err, HasSubstr("does not exist"));
  EXPECT_THAT(r.err, HasSubstr(dir.File("no/such/dir")));
  EXPECT_FALSE(std::filesystem::exists(dir.File("no")));
}

TEST(MapdProcessTest, AFileThatIsNotADatabaseIsRefusedAndLeftAlone) {
  TempDir dir;
  const std::string junk(4096, 'j');
  std::ofstream(dir.File("junk.db")) << junk;
  const CommandResult r =
      RunCommand({MAPD_BINARY, "--db", dir.File("junk.db"), "--listen", "127.0.0.1:0"});
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_THAT(r.err, HasSubstr("not a database"));
  std::ifstream in(dir.File("junk.db"));
  std::string back((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_EQ(back, junk);
}

TEST(MapdProcessTest, APortInUseIsReportedClearly) {
  TempDir dir;
  MapdProcess first = StartMapd(dir.File("a.db"));
  ASSERT_GT(first.port, 0) << first.log();
  const CommandResult r =
      RunCommand({MAPD_BINARY, "--db", dir.File("b.db"), "--listen", first.address});
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_THAT(r.err, HasSubstr("cannot listen"));
  EXPECT_EQ(Stop(first.pid, SIGTERM), 0);
}

TEST(MapdProcessTest, SigtermWhileRobotsStreamLosesNoAcknowledgedBatch) {
  TempDir dir;
  MapdProcess mapd = StartMapd(dir.File("map.db"), {"--shutdown_grace_s", "2"});
  ASSERT_GT(mapd.port, 0) << mapd.log();
  auto stub = pb::MapService::NewStub(
      grpc::CreateChannel(mapd.address, grpc::InsecureChannelCredentials()));
  grpc::ClientContext ctx;
  auto stream = stub->Ingest(&ctx);
  std::atomic<int> stored{0};
  std::thread reader([&] {
    pb::IngestAck ack;
    while (stream->Read(&ack)) stored += ack.result() == pb::IngestAck::STORED;
  });
  std::mt19937_64 rng(3);
  bool terminated = false;
  // SIGTERM once some batches are acknowledged, while more are still being written.
  for (uint64_t seq = 1; seq <= 5000; ++seq) {
    if (!stream->Write(RoomBatch("r1", "s1", seq, 5, 4, 0.01 * static_cast<double>(seq), &rng)))
      break;
    if (!terminated && stored >= 100) {
      kill(mapd.pid, SIGTERM);
      terminated = true;
    }
  }
  for (int i = 0; i < 1000 && !terminated && stored < 100; ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  if (!terminated) kill(mapd.pid, SIGTERM);
  stream->WritesDone();
  reader.join();
  stream->Finish();
  EXPECT_EQ(Stop(mapd.pid, SIGTERM), 0) << mapd.log();
  EXPECT_THAT(mapd.log(), HasSubstr("event=stopped"));
  EXPECT_GT(stored.load(), 0);

  // Everything acknowledged is in the database after the restart.
  mapd = StartMapd(dir.File("map.db"));
  ASSERT_GT(mapd.port, 0) << mapd.log();
  auto stub2 = pb::MapService::NewStub(
      grpc::CreateChannel(mapd.address, grpc::InsecureChannelCredentials()));
  grpc::ClientContext ctx2;
  pb::Stats stats;
  ASSERT_TRUE(stub2->GetStats(&ctx2, {}, &stats).ok());
  EXPECT_GE(stats.batches(), static_cast<uint64_t>(stored.load()));
  EXPECT_EQ(Stop(mapd.pid, SIGTERM), 0);
}

// A parked robot keeps its stream open and sends nothing: SIGTERM ends its
// stream at once with UNAVAILABLE (after acknowledging what it sent) instead
// of waiting out shutdown_grace_s, which is 60 s here so that the margin is
// wide on any machine.
TEST(MapdProcessTest, SigtermEndsAnIdleRobotStreamAtOnce) {
  TempDir dir;
  MapdProcess mapd = StartMapd(dir.File("map.db"), {"--shutdown_grace_s", "60"});
  ASSERT_GT(mapd.port, 0) << mapd.log();
  auto stub = pb::MapService::NewStub(
      grpc::CreateChannel(mapd.address, grpc::InsecureChannelCredentials()));
  grpc::ClientContext ctx;
  auto stream = stub->Ingest(&ctx);
  std::mt19937_64 rng(4);
  ASSERT_TRUE(stream->Write(RoomBatch("parked", "s1", 1, 5, 4, 0, &rng)));
  pb::IngestAck ack;
  ASSERT_TRUE(stream->Read(&ack));
  EXPECT_EQ(ack.result(), pb::IngestAck::STORED);

  const auto t0 = std::chrono::steady_clock::now();
  EXPECT_EQ(Stop(mapd.pid, SIGTERM, std::chrono::seconds(90)), 0) << mapd.log();
  EXPECT_LT(std::chrono::steady_clock::now() - t0, std::chrono::seconds(30));
  EXPECT_FALSE(stream->Read(&ack));
  const grpc::Status end = stream->Finish();
  EXPECT_EQ(end.error_code(), grpc::StatusCode::UNAVAILABLE);
  EXPECT_THAT(end.error_message(), HasSubstr("shutting down"));
  EXPECT_THAT(mapd.log(), HasSubstr("shutdown=true"));
}

// A restart whose replay is held (MAPD_TEST_HOLD_FUSER_FILE, so that recovery
// cannot finish before the test looks, on a machine of any speed): mapd listens
// at once, says NOT_SERVING and refuses ingest (UNAVAILABLE, nothing stored)
// while it recovers, then SERVING once let go, every observation replayed.
TEST(MapdProcessTest, ListensAtOnceAndIsNotServingWhileRecovering) {
  TempDir dir;
  const std::string db = dir.File("map.db");
  // No snapshots: the restart replays every stored observation.
  const std::vector<std::string> args = {"--snapshot.every_observations", "0"};
  constexpr uint64_t kBatches = 1000;
  MapdProcess mapd = StartMapd(db, args);
  ASSERT_GT(mapd.port, 0) << mapd.log();
  EXPECT_EQ(CheckHealth(mapd.address), Health::kServing);
  std::mt19937_64 rng(5);
  {
    auto stub = pb::MapService::NewStub(
        grpc::CreateChannel(mapd.address, grpc::InsecureChannelCredentials()));
    grpc::ClientContext ctx;
    auto stream = stub->Ingest(&ctx);
    std::thread reader([&] {
      pb::IngestAck ack;
      while (stream->Read(&ack)) {
      }
    });
    for (uint64_t seq = 1; seq <= kBatches; ++seq) {
      ASSERT_TRUE(
          stream->Write(RoomBatch("r1", "s1", seq, 5, 4, 0.001 * static_cast<double>(seq), &rng)));
    }
    stream->WritesDone();
    reader.join();
    ASSERT_TRUE(stream->Finish().ok());
  }
  ASSERT_EQ(Stop(mapd.pid, SIGTERM, std::chrono::seconds(120)), 0) << mapd.log();

  const std::string hold = dir.File("hold-fuser");
  std::ofstream(hold) << "held\n";
  mapd = StartMapd(db, args, kDefaultMapdBinary, std::chrono::seconds(20), "listening", "",
                   {"MAPD_TEST_HOLD_FUSER_FILE=" + hold});
  ASSERT_GT(mapd.port, 0) << mapd.log();
  EXPECT_THAT(mapd.log(), HasSubstr("event=fuser_held_for_test"));
  EXPECT_EQ(CheckHealth(mapd.address), Health::kNotServing);
  {
    auto stub = pb::MapService::NewStub(
        grpc::CreateChannel(mapd.address, grpc::InsecureChannelCredentials()));
    grpc::ClientContext ctx;
    ctx.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(60));
    auto stream = stub->Ingest(&ctx);
    stream->Write(RoomBatch("r1", "s1", kBatches + 1, 5, 4, 0.0, &rng));  // may find it closed
    stream->WritesDone();
    pb::IngestAck ack;
    EXPECT_FALSE(stream->Read(&ack)) << "acknowledged while recovering: " << ack.DebugString();
    const grpc::Status s = stream->Finish();
    EXPECT_EQ(s.error_code(), grpc::StatusCode::UNAVAILABLE) << s.error_message();
    EXPECT_THAT(s.error_message(), HasSubstr("recovering"));
  }
  EXPECT_THAT(mapd.log(), ::testing::Not(HasSubstr("event=serving")));

  ASSERT_EQ(unlink(hold.c_str()), 0);
  Health now = Health::kNotServing;
  for (int i = 0; i < 6000 && now != Health::kServing; ++i) {  // up to 2 min (sanitizers)
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
    now = CheckHealth(mapd.address);
  }
  EXPECT_EQ(now, Health::kServing) << mapd.log();
  EXPECT_THAT(mapd.log(),
              HasSubstr("event=map_recovered from=scratch replayed=" + std::to_string(kBatches)));
  auto stub = pb::MapService::NewStub(
      grpc::CreateChannel(mapd.address, grpc::InsecureChannelCredentials()));
  grpc::ClientContext ctx;
  pb::Stats stats;
  ASSERT_TRUE(stub->GetStats(&ctx, {}, &stats).ok());
  EXPECT_EQ(stats.batches(), kBatches);  // the batch sent while recovering was not stored
  EXPECT_EQ(Stop(mapd.pid, SIGTERM), 0);
}

}  // namespace
}  // namespace mapd::testing
