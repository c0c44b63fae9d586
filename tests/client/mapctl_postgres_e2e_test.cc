// mapd on PostgreSQL (--store), driven through mapctl as an operator would:
// maps kept in a database the test starts itself (tests/common/postgres.h),
// across a restart, one mapd per map at a time, and no password on the
// command line.
#include <gmock/gmock.h>
#include <grpcpp/grpcpp.h>
#include <gtest/gtest.h>
#include <signal.h>

#include <cstdio>
#include <string>
#include <thread>
#include <vector>

#include "client/robot/robot_client.h"
#include "client/sim_robot.h"
#include "common/postgres.h"
#include "common/process.h"
#include "common/temp_dir.h"

namespace mapd::testing {
namespace {

using ::testing::HasSubstr;
using ::testing::Not;

class MapdOnPostgresTest : public ::testing::Test {
 protected:
  void SetUp() override {
    PostgresCluster* cluster = PostgresCluster::Shared();
    if (cluster == nullptr) GTEST_SKIP() << "no PostgreSQL (install postgresql-15)";
    store_ = cluster->NewDatabase();
  }
  MapdProcess Start(const std::string& log_name) {
    return StartMapd("", {"--store", store_, "--limits.read_wait_s", "120"}, MAPD_BINARY,
                     std::chrono::seconds(60), "serving", dir_.File(log_name));
  }
  // One of several instances on the database: named `name`, started until
  // its log says `ready` ("serving" for the first, "listening" for others).
  MapdProcess StartInstance(const std::string& name, const char* ready,
                            std::vector<std::string> extra = {}) {
    std::vector<std::string> args = {"--store", store_, "--instance_name", name};
    args.insert(args.end(), extra.begin(), extra.end());
    return StartMapd("", args, MAPD_BINARY, std::chrono::seconds(60), ready,
                     dir_.File(name + ".log"));
  }
  CommandResult Mapctl(const MapdProcess& mapd, std::vector<std::string> args) {
    args.insert(args.begin(), {MAPCTL_BINARY, "--server", mapd.address});
    return RunCommand(args, "", std::chrono::seconds(120));
  }

  TempDir dir_;
  std::string store_;
};

TEST_F(MapdOnPostgresTest, MapsLiveInTheDatabaseAcrossARestart) {
  MapdProcess mapd = Start("first.log");
  ASSERT_GT(mapd.port, 0) << mapd.log();
  EXPECT_THAT(mapd.log(), HasSubstr("store=postgresql"));
  CommandResult r = Mapctl(mapd, {"simulate", "--robots", "2", "--scans", "40"});
  ASSERT_EQ(r.exit_code, 0) << r.out << r.err;
  EXPECT_THAT(r.out, HasSubstr("80 stored"));
  r = Mapctl(mapd, {"maps", "create", "site-1", "--set", "fusion.eta_m=0.25"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  r = Mapctl(mapd,
             {"--map", "site-1", "simulate", "--robots", "1", "--scans", "30", "--session", "s1"});
  ASSERT_EQ(r.exit_code, 0) << r.out << r.err;
  EXPECT_THAT(r.out, HasSubstr("30 stored"));
  const CommandResult before = Mapctl(mapd, {"features", "--format", "json"});
  ASSERT_EQ(before.exit_code, 0) << before.err;
  EXPECT_THAT(before.out, HasSubstr("sim-robot-2"));
  EXPECT_EQ(Stop(mapd.pid, SIGTERM), 0) << mapd.log();

  // Another mapd on the same database serves the same maps, as they were.
  MapdProcess again = Start("second.log");
  ASSERT_GT(again.port, 0) << again.log();
  // Once site-1 is open. Leased here while it opens, it is listed "not
  // serving", never "served by" this mapd's own address.
  r = RunUntil([&] { return Mapctl(again, {"maps"}); },
               [](const CommandResult& c) {
                 EXPECT_EQ(c.out.find("served by"), std::string::npos) << c.out;
                 return c.exit_code == 0 && c.out.find("not serving") == std::string::npos;
               });
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_THAT(r.out, HasSubstr("site-1"));
  EXPECT_THAT(r.out, HasSubstr("fusion.eta_m=0.25"));
  r = Mapctl(again, {"status", "--json"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_THAT(r.out, HasSubstr("\"batches\": 80"));
  EXPECT_THAT(r.out, HasSubstr("postgresql map default"));
  const CommandResult after = Mapctl(again, {"features", "--format", "json"});
  ASSERT_EQ(after.exit_code, 0) << after.err;
  EXPECT_EQ(after.out, before.out) << "the fused map is recovered from the database";
  r = Mapctl(again,
             {"--map", "site-1", "simulate", "--robots", "1", "--scans", "30", "--session", "s1"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_THAT(r.out, HasSubstr("30 duplicate"));

  EXPECT_EQ(Stop(again.pid, SIGTERM), 0) << again.log();
}

// Failover: a second mapd on the database serves none of the first's maps
// and redirects their calls to it; killed, the first's maps move to the
// second within a few leases, with everything it acknowledged.
// A client that knows only `via` (no redirects followed): its calls and
// streams are forwarded to `owner` and answered there.
void ExpectForwardedBy(const MapdProcess& via, const MapdProcess& owner) {
  auto stub = mapserver::v1::MapService::NewStub(
      grpc::CreateChannel(via.address, grpc::InsecureChannelCredentials()));
  grpc::ClientContext call;
  mapserver::v1::Stats stats;
  const grpc::Status s = stub->GetStats(&call, mapserver::v1::GetStatsRequest(), &stats);
  ASSERT_TRUE(s.ok()) << s.error_message();
  EXPECT_EQ(stats.batches(), 80u);
  // A server stream, relayed message by message.
  grpc::ClientContext read;
  mapserver::v1::FeatureMapRequest request;
  request.set_max_wait_ms(5000);
  auto pages = stub->GetFeatureMap(&read, request);
  mapserver::v1::FeatureMapPage page;
  size_t features = 0;
  while (pages->Read(&page)) features += static_cast<size_t>(page.features_size());
  ASSERT_TRUE(pages->Finish().ok());
  EXPECT_GT(features, 0u);
  // A call forwarded already is not forwarded again (no loop between two
  // instances with stale views): redirected.
  grpc::ClientContext again;
  again.AddMetadata("mapd-forwarded-by", "another");
  EXPECT_EQ(stub->GetStats(&again, mapserver::v1::GetStatsRequest(), &stats).error_code(),
            grpc::StatusCode::UNAVAILABLE);
  EXPECT_EQ(again.GetServerTrailingMetadata().count("mapd-map-owner"), 1u);
  // A stream of batches, relayed both ways: the owner stores and acknowledges.
  {
    client::SimRobotParams params;
    params.robot_id = "relayed";
    client::SimRobot robot(client::DefaultWorld(), params);
    grpc::ClientContext ingest;
    auto stream = stub->Ingest(&ingest);
    for (int i = 0; i < 3; ++i) ASSERT_TRUE(stream->Write(robot.NextBatch()));
    stream->WritesDone();
    mapserver::v1::IngestAck ack;
    int stored = 0;
    while (stream->Read(&ack)) stored += ack.result() == mapserver::v1::IngestAck::STORED ? 1 : 0;
    const grpc::Status end = stream->Finish();
    EXPECT_TRUE(end.ok()) << end.error_message();
    EXPECT_EQ(stored, 3);
  }
  // An upload, relayed: the owner's verdict comes back (here a refusal).
  {
    grpc::ClientContext upload;
    mapserver::v1::SubmapInfo info;
    auto writer = stub->UploadSubmap(&upload, &info);
    mapserver::v1::UploadSubmapRequest part;
    part.mutable_header()->set_robot_id("relayed");
    part.mutable_header()->set_name("not-a-map");
    part.mutable_header()->set_format(mapserver::v1::SUBMAP_FORMAT_OCTOMAP_BT);
    ASSERT_TRUE(writer->Write(part));
    part.set_chunk("these bytes are no OctoMap");
    writer->Write(part);
    writer->WritesDone();
    const grpc::Status refused = writer->Finish();
    EXPECT_EQ(refused.error_code(), grpc::StatusCode::INVALID_ARGUMENT) << refused.error_message();
  }
  // The stream of a client already forwarded once: redirected, the owner in
  // the trailing metadata.
  grpc::ClientContext ingest;
  ingest.AddMetadata("mapd-forwarded-by", "another");
  auto stream = stub->Ingest(&ingest);
  stream->WritesDone();
  mapserver::v1::IngestAck ack;
  while (stream->Read(&ack)) {
  }
  const grpc::Status refused = stream->Finish();
  EXPECT_EQ(refused.error_code(), grpc::StatusCode::UNAVAILABLE);
  EXPECT_THAT(refused.error_message(), HasSubstr("is served by the mapd at " + owner.address));
  const auto& trailing = ingest.GetServerTrailingMetadata();
  auto named = trailing.find("mapd-map-owner");
  ASSERT_NE(named, trailing.end());
  EXPECT_EQ(std::string(named->second.data(), named->second.size()), owner.address);
}

TEST_F(MapdOnPostgresTest, ASecondMapdTakesTheMapsOfAKilledOne) {
  // Named so that rendezvous hashing leaves "default" with the first (no
  // handoff to the second before the kill).
  MapdProcess first = StartInstance("mapd-1", "serving", {"--lease_ttl_s", "1"});
  ASSERT_GT(first.port, 0) << first.log();
  CommandResult r = Mapctl(first, {"simulate", "--robots", "2", "--scans", "40"});
  ASSERT_EQ(r.exit_code, 0) << r.out << r.err;

  MapdProcess second = StartInstance("mapd-2", "listening", {"--lease_ttl_s", "1"});
  ASSERT_GT(second.port, 0) << second.log();
  ExpectForwardedBy(second, first);  // 80 batches, then 3 relayed
  const CommandResult before = Mapctl(first, {"features", "--format", "json"});
  ASSERT_EQ(before.exit_code, 0) << before.err;
  // mapctl asks any instance and goes to the owner by itself.
  r = Mapctl(second, {"status", "--json"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_THAT(r.out, HasSubstr("\"batches\": 83"));
  r = Mapctl(second, {"maps"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_THAT(r.out, HasSubstr("served by " + first.address));

  Stop(first.pid, SIGKILL);
  const auto killed = std::chrono::steady_clock::now();
  for (;;) {
    r = Mapctl(second, {"status", "--json"});
    if (r.exit_code == 0 || std::chrono::steady_clock::now() - killed > std::chrono::seconds(20)) {
      break;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  ASSERT_EQ(r.exit_code, 0) << r.err << second.log();
  const double took_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - killed).count();
  EXPECT_LT(took_s, 10.0) << "takeover with 1 s leases";
  std::printf("takeover after kill -9, 1 s leases: %.2f s\n", took_s);
  EXPECT_THAT(r.out, HasSubstr("\"batches\": 83"));
  EXPECT_THAT(second.log(), HasSubstr("event=map_taken map=default epoch=2"));
  // The fused map is recovered in the background (slow under sanitizers).
  CommandResult after = Mapctl(second, {"features", "--format", "json"});
  for (int i = 0; i < 300 && after.exit_code != 0; ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
    after = Mapctl(second, {"features", "--format", "json"});
  }
  ASSERT_EQ(after.exit_code, 0) << after.err;
  EXPECT_EQ(after.out, before.out) << "the fused map is recovered from the database";
  EXPECT_EQ(Stop(second.pid, SIGTERM), 0) << second.log();
}

// A relayed stream holds a place under the relaying instance's
// limits.max_streams, as a local one does: relaying is no way around them.
TEST_F(MapdOnPostgresTest, ARelayingInstanceCountsTheStreamsItRelays) {
  MapdProcess first = StartInstance("mapd-1", "serving");
  ASSERT_GT(first.port, 0) << first.log();
  MapdProcess second = StartInstance("mapd-2", "listening", {"--limits.max_streams", "1"});
  ASSERT_GT(second.port, 0) << second.log();
  auto stub = mapserver::v1::MapService::NewStub(
      grpc::CreateChannel(second.address, grpc::InsecureChannelCredentials()));
  client::SimRobotParams params;
  params.robot_id = "relayed";
  client::SimRobot robot(client::DefaultWorld(), params);
  // One stream relayed to the owner, held open (a batch acknowledged through it).
  grpc::ClientContext held;
  auto open = stub->Ingest(&held);
  ASSERT_TRUE(open->Write(robot.NextBatch()));
  mapserver::v1::IngestAck ack;
  ASSERT_TRUE(open->Read(&ack));
  EXPECT_EQ(ack.result(), mapserver::v1::IngestAck::STORED);
  // The second at once is refused by the relaying instance, naming the limit.
  const auto one_batch = [&](grpc::ClientContext* call) {
    auto stream = stub->Ingest(call);
    stream->Write(robot.NextBatch());
    stream->WritesDone();
    while (stream->Read(&ack)) {
    }
    return stream->Finish();
  };
  grpc::ClientContext second_call;
  const grpc::Status refused = one_batch(&second_call);
  EXPECT_EQ(refused.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED) << refused.error_message();
  EXPECT_THAT(refused.error_message(), HasSubstr("limits.max_streams = 1"));
  EXPECT_THAT(second.log(), HasSubstr("event=stream_refused rpc=Ingest"));
  // Once the first ends, its place is free again (the relay lets it go when
  // both its calls are done, just after the client sees the end).
  open->WritesDone();
  while (open->Read(&ack)) {
  }
  ASSERT_TRUE(open->Finish().ok());
  grpc::Status later;
  for (int i = 0; i < 50; ++i) {
    grpc::ClientContext call;
    later = one_batch(&call);
    if (later.error_code() != grpc::StatusCode::RESOURCE_EXHAUSTED) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  EXPECT_TRUE(later.ok()) << later.error_message();
  EXPECT_EQ(Stop(first.pid, SIGTERM), 0) << first.log();
  EXPECT_EQ(Stop(second.pid, SIGTERM), 0) << second.log();
}

// --forward false: every call for a map served elsewhere is redirected.
TEST_F(MapdOnPostgresTest, WithoutForwardingCallsAreRedirected) {
  MapdProcess first = StartInstance("mapd-1", "serving", {"--forward", "false"});
  ASSERT_GT(first.port, 0) << first.log();
  MapdProcess second = StartInstance("mapd-2", "listening", {"--forward", "false"});
  ASSERT_GT(second.port, 0) << second.log();
  auto stub = mapserver::v1::MapService::NewStub(
      grpc::CreateChannel(second.address, grpc::InsecureChannelCredentials()));
  grpc::ClientContext call;
  mapserver::v1::Stats stats;
  const grpc::Status s = stub->GetStats(&call, mapserver::v1::GetStatsRequest(), &stats);
  EXPECT_EQ(s.error_code(), grpc::StatusCode::UNAVAILABLE);
  EXPECT_THAT(s.error_message(), HasSubstr("is served by the mapd at " + first.address));
  const auto& trailing = call.GetServerTrailingMetadata();
  auto owner = trailing.find("mapd-map-owner");
  ASSERT_NE(owner, trailing.end());
  EXPECT_EQ(std::string(owner->second.data(), owner->second.size()), first.address);
  // mapctl follows the redirect.
  const CommandResult r = Mapctl(second, {"status", "--json"});
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(Stop(first.pid, SIGTERM), 0) << first.log();
  EXPECT_EQ(Stop(second.pid, SIGTERM), 0) << second.log();
}

// DeleteMap and RestoreMap with two mapd on one database: asked of either,
// done by the map's owner; an archived map is served by neither, and comes
// back as it was.
TEST_F(MapdOnPostgresTest, AMapIsArchivedRestoredAndPurgedThroughEitherInstance) {
  MapdProcess first = StartInstance("mapd-1", "serving");
  ASSERT_GT(first.port, 0) << first.log();
  MapdProcess second = StartInstance("mapd-2", "listening");
  ASSERT_GT(second.port, 0) << second.log();
  CommandResult r = Mapctl(first, {"maps", "create", "site-1"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  r = Mapctl(first, {"--map", "site-1", "simulate", "--robots", "1", "--scans", "30"});
  ASSERT_EQ(r.exit_code, 0) << r.out << r.err;
  const CommandResult before = Mapctl(first, {"--map", "site-1", "features", "--format", "json"});
  ASSERT_EQ(before.exit_code, 0) << before.err;

  // Asked of the instance that does not serve it: mapctl follows the redirect.
  r = Mapctl(second, {"maps", "delete", "site-1"});
  ASSERT_EQ(r.exit_code, 0) << r.err << first.log();
  EXPECT_THAT(r.out, HasSubstr("archived map site-1 (postgresql)"));
  for (const MapdProcess* mapd : {&first, &second}) {
    r = Mapctl(*mapd, {"maps"});
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_THAT(r.out, Not(HasSubstr("site-1"))) << mapd->address;
    r = Mapctl(*mapd, {"--map", "site-1", "status"});
    EXPECT_EQ(r.exit_code, 1) << r.out;
    EXPECT_THAT(r.err, HasSubstr("site-1"));
  }
  r = Mapctl(second, {"maps", "--archived"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_THAT(r.out, HasSubstr("site-1"));
  r = Mapctl(first, {"maps", "create", "site-1"});
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_THAT(r.err, HasSubstr("is archived"));

  r = Mapctl(second, {"maps", "restore", "site-1"});
  ASSERT_EQ(r.exit_code, 0) << r.err << second.log();
  EXPECT_THAT(r.out, HasSubstr("restored map site-1"));
  CommandResult after = Mapctl(first, {"--map", "site-1", "features", "--format", "json"});
  for (int i = 0; i < 100 && after.out != before.out; ++i) {  // a handoff may be under way
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
    after = Mapctl(first, {"--map", "site-1", "features", "--format", "json"});
  }
  EXPECT_EQ(after.out, before.out) << after.err;

  r = Mapctl(first, {"maps", "delete", "site-1", "--purge"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_THAT(r.out, HasSubstr("deleted map site-1 for good"));
  r = Mapctl(second, {"maps", "--archived"});
  EXPECT_THAT(r.out, Not(HasSubstr("site-1")));
  r = Mapctl(second, {"maps", "create", "site-1"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  r = Mapctl(second, {"--map", "site-1", "robots", "--json"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_THAT(r.out, Not(HasSubstr("sim-robot"))) << "a new map, empty";
  EXPECT_EQ(Stop(first.pid, SIGTERM), 0) << first.log();
  EXPECT_EQ(Stop(second.pid, SIGTERM), 0) << second.log();
}

// The first admin token from the database, beside the running mapd (tokens
// are the database's, whichever map or mapd).
TEST_F(MapdOnPostgresTest, TokensBootstrapFromTheDatabaseWhileMapdRuns) {
  MapdProcess mapd = Start("mapd.log");
  ASSERT_GT(mapd.port, 0) << mapd.log();
  CommandResult r = RunCommand(
      {MAPD_BINARY, "token", "create", "--store", store_, "--role", "admin", "--name", "root"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::string admin = r.out.substr(0, r.out.find('\n'));
  ASSERT_EQ(admin.rfind("mapd_", 0), 0u) << r.out;
  r = Mapctl(mapd, {"status"});  // a token exists now: no anonymous calls
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_THAT(r.err, HasSubstr("UNAUTHENTICATED"));
  r = Mapctl(mapd, {"--token", admin, "whoami"});
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_THAT(r.out, HasSubstr("root (role admin"));
  r = Mapctl(mapd, {"--token", admin, "audit"});
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_THAT(r.out, HasSubstr("mapd token (offline)"));
  r = RunCommand({MAPD_BINARY, "token", "list", "--store", store_});
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_THAT(r.out, HasSubstr("root"));
  EXPECT_EQ(Stop(mapd.pid, SIGTERM), 0) << mapd.log();
}

TEST_F(MapdOnPostgresTest, APasswordOnTheCommandLineIsRefused) {
  const CommandResult r =
      RunCommand({MAPD_BINARY, "--store", store_ + " password=hunter2", "--listen", "127.0.0.1:0"});
  EXPECT_NE(r.exit_code, 0);
  EXPECT_THAT(r.err, HasSubstr("holds a password"));
  EXPECT_THAT(r.err, HasSubstr("PGPASSWORD"));
  EXPECT_THAT(r.err, ::testing::Not(HasSubstr("hunter2")));
  const CommandResult both =
      RunCommand({MAPD_BINARY, "--store", store_, "--db", dir_.File("map.db")});
  EXPECT_NE(both.exit_code, 0);
  EXPECT_THAT(both.err, HasSubstr("store is set with db"));
}

TEST_F(MapdOnPostgresTest, AnUnreachableServerIsAClearError) {
  const CommandResult r =
      RunCommand({MAPD_BINARY, "--store", "host=" + dir_.path() + " port=1 dbname=x", "--listen",
                  "127.0.0.1:0"},
                 "", std::chrono::seconds(60));
  EXPECT_NE(r.exit_code, 0);
  EXPECT_THAT(r.err, HasSubstr("cannot connect to PostgreSQL"));
}

// PostgreSQL restarted under a robot streaming into mapd (fsync on, its own
// cluster): the robot's batches are refused while it is away, resent after,
// and every one ends up stored exactly once.
TEST(MapdPostgresRestartTest, ARobotRidesOutAPostgresRestart) {
  std::string why;
  std::unique_ptr<PostgresCluster> cluster = PostgresCluster::Start(/*fsync=*/true, &why);
  if (cluster == nullptr) GTEST_SKIP() << "no PostgreSQL (install postgresql-15): " << why;
  TempDir dir;
  MapdProcess mapd = StartMapd("", {"--store", cluster->NewDatabase()}, MAPD_BINARY,
                               std::chrono::seconds(60), "serving", dir.File("mapd.log"));
  ASSERT_GT(mapd.port, 0) << mapd.log();
  robot::RobotClientOptions options;
  options.give_up_after = std::chrono::seconds(60);
  robot::RobotClient client(grpc::CreateChannel(mapd.address, grpc::InsecureChannelCredentials()),
                            options);
  client::SimRobotParams params;
  params.robot_id = "pg-robot";
  params.session_id = "restart";
  client::SimRobot robot(client::DefaultWorld(), params);
  constexpr int kBatches = 300;
  for (int i = 0; i < kBatches; ++i) {
    if (i == 100) {
      ASSERT_TRUE(cluster->Stop("fast"));
    }
    if (i == 150) {
      ASSERT_TRUE(cluster->Restart(&why)) << why;
    }
    client.Send(robot.NextBatch());
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  ASSERT_TRUE(client.WaitForAcks(std::chrono::seconds(90))) << mapd.log();
  const robot::IngestCounts counts = client.counts();
  EXPECT_EQ(counts.stored + counts.duplicate, static_cast<uint64_t>(kBatches));
  EXPECT_EQ(counts.rejected, 0u);
  EXPECT_GT(counts.reconnects, 0u) << "the refused batches came back on a new stream";
  const CommandResult r = RunCommand({MAPCTL_BINARY, "--server", mapd.address, "status", "--json"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_THAT(r.out, HasSubstr("\"batches\": " + std::to_string(kBatches)));
  EXPECT_THAT(mapd.log(), HasSubstr("event=writable_again"));
  EXPECT_EQ(Stop(mapd.pid, SIGTERM), 0) << mapd.log();
}

}  // namespace
}  // namespace mapd::testing
