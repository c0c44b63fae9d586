// The mapd binary as an operator meets it: bad flags, a damaged database,
// SIGTERM with robots still streaming.
#include <atomic>
#include <fstream>
#include <thread>

#include <gmock/gmock.h>
#include <grpcpp/grpcpp.h>
#include <gtest/gtest.h>

#include "common/batches.h"
#include "common/process.h"
#include "common/temp_dir.h"
#include "mapserver/v1/map_service.grpc.pb.h"

namespace mapd::testing {
namespace {

namespace pb = mapserver::v1;
using ::testing::HasSubstr;

TEST(MapdProcessTest, ABadFlagExitsTwoNamingTheSetting) {
  TempDir dir;
  const CommandResult r = RunCommand({MAPD_BINARY, "--db", dir.File("m.db"), "--fusion.gamma", "7"});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.err, HasSubstr("gamma"));
}

TEST(MapdProcessTest, HelpListsTheSettings) {
  const CommandResult r = RunCommand({MAPD_BINARY, "--help"});
  EXPECT_EQ(r.exit_code, 0);
  EXPECT_THAT(r.out, HasSubstr("--fusion.eta_m"));
  EXPECT_THAT(r.out, HasSubstr("--sync"));
}

TEST(MapdProcessTest, AFileThatIsNotADatabaseIsRefusedAndLeftAlone) {
  TempDir dir;
  const std::string junk(4096, 'j');
  std::ofstream(dir.File("junk.db")) << junk;
  const CommandResult r = RunCommand({MAPD_BINARY, "--db", dir.File("junk.db"), "--listen", "127.0.0.1:0"});
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
  const CommandResult r = RunCommand({MAPD_BINARY, "--db", dir.File("b.db"), "--listen", first.address});
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_THAT(r.err, HasSubstr("cannot listen"));
  EXPECT_EQ(Stop(first.pid, SIGTERM), 0);
}

TEST(MapdProcessTest, SigtermWhileRobotsStreamLosesNoAcknowledgedBatch) {
  TempDir dir;
  MapdProcess mapd = StartMapd(dir.File("map.db"), {"--shutdown_grace_s", "2"});
  ASSERT_GT(mapd.port, 0) << mapd.log();
  auto stub = pb::MapService::NewStub(grpc::CreateChannel(mapd.address, grpc::InsecureChannelCredentials()));
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
    if (!stream->Write(RoomBatch("r1", "s1", seq, 5, 4, 0.01 * static_cast<double>(seq), &rng))) break;
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
  auto stub2 = pb::MapService::NewStub(grpc::CreateChannel(mapd.address, grpc::InsecureChannelCredentials()));
  grpc::ClientContext ctx2;
  pb::Stats stats;
  ASSERT_TRUE(stub2->GetStats(&ctx2, {}, &stats).ok());
  EXPECT_GE(stats.batches(), static_cast<uint64_t>(stored.load()));
  EXPECT_EQ(Stop(mapd.pid, SIGTERM), 0);
}

}  // namespace
}  // namespace mapd::testing
