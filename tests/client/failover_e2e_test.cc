// Failover with three mapd processes on one PostgreSQL (docs/scale-out.md,
// sections 3-4), driven as a fleet would: maps spread over the instances by
// rendezvous hashing, robots streaming with RobotClient given every
// instance's address, then an owner killed (-9), frozen (SIGSTOP), or each
// instance restarted in turn (SIGTERM, a rolling restart). What must hold:
// the maps acknowledge batches again from another process within seconds,
// every batch a robot sent is stored exactly once, a frozen owner that wakes
// after a takeover commits nothing, and a rolling restart pauses each map's
// ingest briefly and refuses nothing.
#include <gmock/gmock.h>
#include <grpcpp/grpcpp.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <map>
#include <memory>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "client/robot/robot_client.h"
#include "client/support/ack_monitor.h"
#include "client/support/streaming_robot.h"
#include "common/postgres.h"
#include "common/process.h"
#include "common/sanitizers.h"
#include "common/temp_dir.h"
#include "service/rendezvous.h"

namespace mapd::testing {
namespace {

namespace pb = mapserver::v1;
using ::testing::HasSubstr;
using Clock = std::chrono::steady_clock;

constexpr int kInstances = 3;
const std::vector<std::string> kMaps = {"default", "site-1", "site-2",
                                        "site-3",  "site-4", "site-5"};

std::string Name(int i) { return "mapd-" + std::to_string(i + 1); }

double SecondsSince(Clock::time_point t) {
  return std::chrono::duration<double>(Clock::now() - t).count();
}

class FailoverTest : public ::testing::Test {
 protected:
  void SetUp() override { StartFleet(PostgresCluster::Shared()); }

  // Three instances on a new database of `cluster`, and the maps.
  void StartFleet(PostgresCluster* cluster) {
    if (cluster == nullptr) GTEST_SKIP() << "no PostgreSQL (install postgresql-15)";
    store_ = cluster->NewDatabase();
    for (int i = 0; i < kInstances; ++i) {
      mapd_.push_back(StartMapd(
          "", {"--store", store_, "--lease_ttl_s", lease_ttl_s_, "--instance_name", Name(i)},
          MAPD_BINARY, std::chrono::seconds(60), i == 0 ? "serving" : "listening",
          dir_.File(Name(i) + ".log")));
      ASSERT_GT(mapd_.back().port, 0) << mapd_.back().log();
      logs_.push_back(mapd_.back().log_path);
      addresses_.push_back(mapd_.back().address);
      names_.push_back(Name(i));
    }
    for (const std::string& map : kMaps) {
      if (map == "default") continue;
      CommandResult r =
          RunCommand({MAPCTL_BINARY, "--server", addresses_[0], "maps", "create", map}, "",
                     std::chrono::seconds(60));
      ASSERT_EQ(r.exit_code, 0) << r.err;
    }
  }

  void TearDown() override {
    if (HasFailure()) {  // who took, dropped and handed off what
      for (const std::string& log_path : logs_) {
        std::string events;
        std::istringstream log(ReadFileBytes(log_path));
        for (std::string line; std::getline(log, line);) {
          if (line.find("event=map_") != std::string::npos ||
              line.find("lease") != std::string::npos ||
              line.find("level=warn") != std::string::npos ||
              line.find("level=error") != std::string::npos) {
            events += line + "\n";
          }
        }
        std::printf("--- %s\n%s", log_path.c_str(), events.c_str());
      }
    }
    robots_.clear();
    for (const MapdProcess& m : mapd_) Stop(m.pid, SIGKILL);
  }

  // Where `map` is served, as instance `asked` says (empty when it cannot say).
  std::string Owner(int asked, const std::string& map) {
    auto stub = pb::MapService::NewStub(Connect(addresses_[asked]));
    grpc::ClientContext call;
    call.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(2));
    pb::LocateMapRequest request;
    request.set_map_id(map);
    pb::MapLocation where;
    if (!stub->LocateMap(&call, request, &where).ok() || !where.live()) return "";
    return where.address();
  }

  // Waits until every map is served by the live instance rendezvous hashing
  // gives it, as every live instance says.
  bool WaitUntilSpread(const std::vector<int>& live, std::chrono::seconds timeout) {
    std::vector<std::string> names;
    for (int i : live) names.push_back(names_[i]);
    const auto deadline = Clock::now() + timeout;
    while (Clock::now() < deadline) {
      bool spread = true;
      for (const std::string& map : kMaps) {
        const std::string want = service::RendezvousPick(map, names);
        const int want_index =
            static_cast<int>(std::find(names_.begin(), names_.end(), want) - names_.begin());
        for (int i : live) spread = spread && Owner(i, map) == addresses_[want_index];
      }
      if (spread) return true;
      std::this_thread::sleep_for(std::chrono::milliseconds(200));
    }
    return false;
  }

  // Waits until instance `i`'s log has `text`.
  bool WaitForLog(int i, const std::string& text, std::chrono::seconds timeout) {
    const auto deadline = Clock::now() + timeout;
    while (ReadFileBytes(mapd_[i].log_path).find(text) == std::string::npos) {
      if (Clock::now() >= deadline) return false;
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
    }
    return true;
  }

  // Starts instance `i` again after it stopped: same name, same port.
  void Restart(int i) {
    mapd_[i] = StartMapd("",
                         {"--store", store_, "--lease_ttl_s", lease_ttl_s_, "--instance_name",
                          Name(i), "--listen", addresses_[i]},
                         MAPD_BINARY, std::chrono::seconds(60), "listening",
                         dir_.File(Name(i) + "-" + std::to_string(++restarts_) + ".log"));
    logs_.push_back(mapd_[i].log_path);
  }

  void StartRobots() {
    for (const std::string& map : kMaps) {
      robots_.push_back(std::make_unique<StreamingRobot>(map, addresses_));
    }
  }

  // Seconds from `since` until every robot of `maps` had a batch acknowledged
  // (negative: not within `timeout`), one figure per map.
  std::map<std::string, double> WaitForAcks(const std::vector<std::string>& maps,
                                            Clock::time_point since, double timeout_s) {
    std::map<std::string, uint64_t> at_start;
    for (const auto& r : robots_) at_start[r->map()] = r->acked();
    std::map<std::string, double> took;
    while (took.size() < maps.size() && SecondsSince(since) < timeout_s) {
      for (const auto& r : robots_) {
        if (std::find(maps.begin(), maps.end(), r->map()) == maps.end()) continue;
        if (took.count(r->map()) == 0 && r->acked() > at_start[r->map()]) {
          took[r->map()] = SecondsSince(since);
        }
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    for (const std::string& m : maps) took.emplace(m, -1.0);
    return took;
  }

  // Stops the robots, waits for every ack, and checks each map stored each
  // batch exactly once: its robot's stored count is what it sent.
  void FinishAndCheckExactlyOnce(int ask) {
    for (auto& r : robots_) r->Stop();
    for (auto& r : robots_) {
      const grpc::Status s = r->client().Finish(std::chrono::seconds(60));
      const robot::IngestCounts c = r->client().counts();
      EXPECT_TRUE(s.ok()) << r->map() << ": " << s.error_message() << " (reconnects "
                          << c.reconnects << ", redirects " << c.redirects << ")";
      EXPECT_EQ(c.rejected, 0u) << r->map();
      EXPECT_EQ(c.stored + c.duplicate, r->sent()) << r->map();
    }
    for (auto& r : robots_) {
      const std::string owner = Owner(ask, r->map());
      ASSERT_FALSE(owner.empty()) << r->map();
      auto stub = pb::MapService::NewStub(Connect(owner));
      grpc::ClientContext call;
      call.AddMetadata("mapd-map-id", r->map());
      pb::ListRobotsResponse robots;
      const grpc::Status s = stub->ListRobots(&call, pb::ListRobotsRequest(), &robots);
      ASSERT_TRUE(s.ok()) << r->map() << ": " << s.error_message();
      ASSERT_EQ(robots.robots_size(), 1) << r->map();
      EXPECT_EQ(robots.robots(0).batches(), r->sent())
          << r->map() << ": every batch sent is stored exactly once";
    }
  }

  // A second-long lease moves a dead owner's maps in seconds (the kill and
  // SIGSTOP tests); a live instance whose writer stalls for half of it gives
  // its maps up, which a loaded CI machine does.
  std::string lease_ttl_s_ = "1";
  TempDir dir_;
  int restarts_ = 0;
  std::vector<std::string> logs_;  // every instance's, restarted ones too
  std::string store_;
  std::vector<MapdProcess> mapd_;
  std::vector<std::string> addresses_, names_;
  std::vector<std::unique_ptr<StreamingRobot>> robots_;
};

TEST_F(FailoverTest, AKilledOwnersMapsMoveWithinSecondsAndNothingIsLost) {
  ASSERT_TRUE(WaitUntilSpread({0, 1, 2}, std::chrono::seconds(30)))
      << "maps spread over the instances by rendezvous hashing";
  StartRobots();
  const std::vector<std::string> all(kMaps.begin(), kMaps.end());
  for (const auto& [map, s] : WaitForAcks(all, Clock::now(), 30)) ASSERT_GE(s, 0) << map;

  // The instance serving the most maps dies.
  std::map<int, std::vector<std::string>> served;
  for (const std::string& map : kMaps) {
    const std::string owner = Owner(0, map);
    for (int i = 0; i < kInstances; ++i) {
      if (addresses_[i] == owner) served[i].push_back(map);
    }
  }
  int victim = 0;
  for (const auto& [i, maps] : served) {
    if (maps.size() > served[victim].size()) victim = i;
  }
  ASSERT_FALSE(served[victim].empty());
  const auto killed = Clock::now();
  Stop(mapd_[victim].pid, SIGKILL);
  const std::map<std::string, double> took = WaitForAcks(served[victim], killed, 30);
  double worst = 0;
  for (const auto& [map, s] : took) {
    EXPECT_GE(s, 0) << map << " never acknowledged again";
    // The benchmark's target is 5 s p50; CI runs loaded, and some jobs sanitized.
    EXPECT_LT(s, kSanitized ? 20.0 : 10.0) << map;
    worst = std::max(worst, s);
    std::printf("kill -9: %s acknowledges again after %.2f s\n", map.c_str(), s);
  }
  std::vector<int> live;
  for (int i = 0; i < kInstances; ++i) {
    if (i != victim) live.push_back(i);
  }
  std::this_thread::sleep_for(std::chrono::seconds(1));
  FinishAndCheckExactlyOnce(live[0]);
  EXPECT_THAT(ReadFileBytes(mapd_[live[0]].log_path) + ReadFileBytes(mapd_[live[1]].log_path),
              HasSubstr("event=map_taken map=" + served[victim][0]));
}

TEST_F(FailoverTest, AFrozenOwnerIsFencedWhenItWakes) {
  ASSERT_TRUE(WaitUntilSpread({0, 1, 2}, std::chrono::seconds(30)));
  StartRobots();
  const std::vector<std::string> all(kMaps.begin(), kMaps.end());
  for (const auto& [map, s] : WaitForAcks(all, Clock::now(), 30)) ASSERT_GE(s, 0) << map;

  // Freeze the owner of site-1 past its lease: the others take its maps.
  const std::string owner = Owner(0, "site-1");
  int frozen = 0;
  while (addresses_[frozen] != owner) ++frozen;
  std::vector<std::string> its_maps;
  for (const std::string& map : kMaps) {
    if (Owner((frozen + 1) % kInstances, map) == owner) its_maps.push_back(map);
  }
  const auto stopped = Clock::now();
  ASSERT_EQ(kill(mapd_[frozen].pid, SIGSTOP), 0);
  // Robots notice the frozen server by keepalive and go to the new owners.
  const std::map<std::string, double> took = WaitForAcks(its_maps, stopped, 60);
  for (const auto& [map, s] : took) {
    EXPECT_GE(s, 0) << map << " never acknowledged again";
    std::printf("SIGSTOP: %s acknowledges again after %.2f s\n", map.c_str(), s);
  }
  // It wakes: its next commit or renewal finds the lease taken over; it drops
  // the maps and redirects.
  ASSERT_EQ(kill(mapd_[frozen].pid, SIGCONT), 0);
  EXPECT_TRUE(WaitForLog(frozen, "event=map_dropped map=site-1", std::chrono::seconds(15)))
      << mapd_[frozen].log();
  std::string now_at;  // the woken instance learns the new owner in its next round
  for (int i = 0; i < 50 && (now_at.empty() || now_at == owner); ++i) {
    now_at = Owner(frozen, "site-1");
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  EXPECT_FALSE(now_at.empty());
  EXPECT_NE(now_at, owner) << "the woken instance redirects to the new owner";
  FinishAndCheckExactlyOnce((frozen + 1) % kInstances);
}

// With a cluster of its own, with fsync on, since it crashes it.
class FailoverPostgresRestartTest : public FailoverTest {
 protected:
  void SetUp() override {
    std::string why;
    cluster_ = PostgresCluster::Start(/*fsync=*/true, &why);
    if (cluster_ == nullptr) GTEST_SKIP() << "no PostgreSQL (install postgresql-15): " << why;
    StartFleet(cluster_.get());
  }
  std::unique_ptr<PostgresCluster> cluster_;
};

TEST_F(FailoverPostgresRestartTest, EveryInstanceCarriesOnAfterPostgresCrashes) {
  ASSERT_TRUE(WaitUntilSpread({0, 1, 2}, std::chrono::seconds(30)));
  StartRobots();
  const std::vector<std::string> all(kMaps.begin(), kMaps.end());
  for (const auto& [map, s] : WaitForAcks(all, Clock::now(), 30)) ASSERT_GE(s, 0) << map;

  // A crash (no checkpoint), away longer than a lease: the robots keep what
  // is not acknowledged, every instance reconnects, and the maps go on.
  ASSERT_TRUE(cluster_->Stop("immediate"));
  std::this_thread::sleep_for(std::chrono::seconds(3));
  std::string why;
  ASSERT_TRUE(cluster_->Restart(&why)) << why;
  const auto back = Clock::now();
  for (const auto& [map, s] : WaitForAcks(all, back, 60)) {
    EXPECT_GE(s, 0) << map << " never acknowledged again";
    std::printf("PostgreSQL back: %s acknowledges again after %.2f s\n", map.c_str(), s);
  }
  for (int i = 0; i < kInstances; ++i) {
    EXPECT_EQ(waitpid(mapd_[i].pid, nullptr, WNOHANG), 0) << Name(i) << " is still running";
  }
  ASSERT_TRUE(WaitUntilSpread({0, 1, 2}, std::chrono::seconds(30)))
      << "every instance is live again and serves its maps";
  // Every batch acknowledged is stored (fsync on), and the resends of those
  // that were not are stored once.
  FinishAndCheckExactlyOnce(0);
}

// A rolling restart hands maps over cleanly (each instance leaves and
// releases its leases), so it needs no short lease: with mapd's default
// (3 s), the pauses measured are the handovers', not lapses of a live
// instance's lease on a slow machine (CI, 2026-12-07: a map paused 16 s
// moving back and forth after one).
class RollingRestartTest : public FailoverTest {
 protected:
  void SetUp() override {
    lease_ttl_s_ = "3";
    FailoverTest::SetUp();
  }
};

TEST_F(RollingRestartTest, EachMapPausesBrieflyAndNothingIsRefused) {
  ASSERT_TRUE(WaitUntilSpread({0, 1, 2}, std::chrono::seconds(30)));
  StartRobots();
  const std::vector<std::string> all(kMaps.begin(), kMaps.end());
  for (const auto& [map, s] : WaitForAcks(all, Clock::now(), 30)) ASSERT_GE(s, 0) << map;

  // Each instance in turn: SIGTERM (it drains, commits and releases its
  // leases), start it again, wait until the maps are spread back to it.
  AckMonitor watch(&robots_);
  for (int i = 0; i < kInstances; ++i) {
    EXPECT_EQ(Stop(mapd_[i].pid, SIGTERM, std::chrono::seconds(30)), 0)
        << Name(i) << " stops cleanly:\n"
        << mapd_[i].log();
    Restart(i);
    ASSERT_GT(mapd_[i].port, 0) << mapd_[i].log();
    // Its maps' leases may still name it (the same name and address) when it
    // is back, so the spread alone does not show it took them again.
    EXPECT_TRUE(WaitForLog(i, "event=map_taken", std::chrono::seconds(30)))
        << Name(i) << " serves maps again after its restart:\n"
        << mapd_[i].log();
    ASSERT_TRUE(WaitUntilSpread({0, 1, 2}, std::chrono::seconds(30)))
        << "maps spread back after " << Name(i) << " restarted";
  }
  // The target, 2 s, is failover_bench's (docs/scale-out.md). This bound only
  // catches a map left stuck: a plain build pauses 1-3 s on a loaded CI host,
  // an ASan build up to ~6 s (CI, 2026-12-07: 5.8 s, every handover clean).
  const double bound_s = kSanitized ? 15.0 : 5.0;
  for (const auto& [map, gap] : watch.Longest()) {
    std::printf("rolling restart: %s paused at most %.2f s\n", map.c_str(), gap);
    EXPECT_LT(gap, bound_s) << map;
  }
  FinishAndCheckExactlyOnce(0);  // which also checks nothing was refused
}

}  // namespace
}  // namespace mapd::testing
