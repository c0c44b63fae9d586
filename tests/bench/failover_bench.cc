// Failover through real mapd processes (docs/scale-out.md, "Failover,
// measured"): three mapd on one PostgreSQL (fsync on), maps spread by
// rendezvous hashing, one robot per map streaming a batch every 20 ms with
// RobotClient given every instance's address. Then, `--kills` times: kill -9
// an instance (each in turn) and time, per map it served, how long until its
// robot's batches are acknowledged again (the takeover); restart the killed
// instance (same name and port) and measure the longest pause in each map's
// acknowledgements while maps are handed back to it (the graceful handoff).
// Then `--rolls` rolling restarts: each instance in turn stopped with SIGTERM
// (it drains, commits and releases its leases) and started again, with the
// longest pause in any map's acknowledgements per restart. At the end every
// robot's batches must be stored exactly once and none refused.
//
//   failover_bench [--kills 20] [--rolls 3] [--maps 6] [--lease_ttl_s S (default: mapd's)]
#include <grpcpp/grpcpp.h>
#include <signal.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "client/support/ack_monitor.h"
#include "client/support/fleet.h"
#include "client/support/streaming_robot.h"
#include "common/process.h"
#include "common/temp_dir.h"
#include "service/rendezvous.h"

namespace {

namespace pb = mapserver::v1;
using Clock = std::chrono::steady_clock;
using mapd::testing::AckMonitor;
using mapd::testing::Fleet;
using mapd::testing::MapdProcess;
using mapd::testing::StreamingRobot;

double Seconds(Clock::duration d) { return std::chrono::duration<double>(d).count(); }

double Percentile(std::vector<double> v, double p) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  return v[static_cast<size_t>(p * static_cast<double>(v.size() - 1) + 0.5)];
}

}  // namespace

int main(int argc, char** argv) {
  int kills = 20, rolls = 3, n_maps = 6;
  std::string ttl;
  for (int i = 1; i + 1 < argc; i += 2) {
    if (!std::strcmp(argv[i], "--kills")) kills = std::atoi(argv[i + 1]);
    if (!std::strcmp(argv[i], "--rolls")) rolls = std::atoi(argv[i + 1]);
    if (!std::strcmp(argv[i], "--maps")) n_maps = std::atoi(argv[i + 1]);
    if (!std::strcmp(argv[i], "--lease_ttl_s")) ttl = argv[i + 1];
  }
  Fleet fleet;
  if (!fleet.StartDatabase()) return 1;
  if (!ttl.empty()) fleet.extra = {"--lease_ttl_s", ttl};
  if (!fleet.Launch(3)) return 1;
  const std::vector<std::string> maps = fleet.CreateMaps(n_maps);
  if (maps.empty()) return 1;
  auto wait_spread = [&](double timeout_s) { return fleet.WaitSpread(maps, timeout_s); };
  if (wait_spread(60) < 0) {
    std::fprintf(stderr, "the maps did not spread over the instances\n");
    return 1;
  }
  std::vector<std::unique_ptr<StreamingRobot>> robots;
  for (const std::string& map : maps) {
    robots.push_back(std::make_unique<StreamingRobot>(map, fleet.addresses));
  }
  AckMonitor monitor(&robots);
  std::this_thread::sleep_for(std::chrono::seconds(3));

  std::vector<double> takeover_s, handback_gap_s;
  for (int k = 0; k < kills; ++k) {
    std::map<int, std::vector<size_t>> served;  // instance -> robots
    for (size_t r = 0; r < robots.size(); ++r) {
      const std::string owner = fleet.Owner(robots[r]->map());
      for (int i = 0; i < 3; ++i) {
        if (fleet.addresses[i] == owner) served[i].push_back(r);
      }
    }
    int victim = k % 3;  // each in turn, unless it serves nothing
    for (const auto& [i, rs] : served) {
      if (served[victim].empty() && !rs.empty()) victim = i;
    }
    std::map<size_t, uint64_t> before;
    for (size_t r : served[victim]) before[r] = robots[r]->acked();
    const auto killed = Clock::now();
    mapd::testing::Stop(fleet.mapd[victim].pid, SIGKILL);
    std::map<size_t, double> took;
    while (took.size() < served[victim].size() && Seconds(Clock::now() - killed) < 60) {
      for (size_t r : served[victim]) {
        if (took.count(r) == 0 && robots[r]->acked() > before[r]) {
          took[r] = Seconds(Clock::now() - killed);
        }
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    double worst = 0;
    for (size_t r : served[victim]) {
      const double s = took.count(r) ? took[r] : 60.0;
      takeover_s.push_back(s);
      worst = std::max(worst, s);
    }
    // Back on its own port: the robots' address lists stay right.
    std::this_thread::sleep_for(std::chrono::milliseconds(500));
    monitor.Reset();
    fleet.mapd[victim] = fleet.Start(victim, fleet.addresses[victim]);
    if (fleet.mapd[victim].port == 0) {
      std::fprintf(stderr, "restart failed:\n%s\n", fleet.mapd[victim].log().c_str());
      return 1;
    }
    const double spread_s = wait_spread(120);
    std::this_thread::sleep_for(std::chrono::seconds(1));
    double gap = 0;
    for (const auto& [map, s] : monitor.Longest()) gap = std::max(gap, s);
    handback_gap_s.push_back(gap);
    std::printf(
        "kill %2d: %s served %zu maps, acknowledged again after %.2f s (worst); "
        "restarted, maps back after %.1f s, longest ack pause meanwhile %.2f s\n",
        k + 1, fleet.names[victim].c_str(), served[victim].size(), worst, spread_s, gap);
    std::fflush(stdout);
  }

  std::vector<double> rolling_gap_s;
  bool clean_stops = true;
  for (int roll = 0; roll < rolls; ++roll) {
    for (int i = 0; i < 3; ++i) {
      monitor.Reset();
      const int code = mapd::testing::Stop(fleet.mapd[i].pid, SIGTERM, std::chrono::seconds(30));
      clean_stops = clean_stops && code == 0;
      fleet.mapd[i] = fleet.Start(i, fleet.addresses[i]);
      if (fleet.mapd[i].port == 0) {
        std::fprintf(stderr, "restart failed:\n%s\n", fleet.mapd[i].log().c_str());
        return 1;
      }
      const double spread_s = wait_spread(120);
      std::this_thread::sleep_for(std::chrono::seconds(1));
      double gap = 0;
      for (const auto& [map, s] : monitor.Longest()) gap = std::max(gap, s);
      rolling_gap_s.push_back(gap);
      std::printf(
          "roll %d, %s: SIGTERM exit %d, maps back after %.1f s, longest ack pause %.2f s\n",
          roll + 1, fleet.names[i].c_str(), code, spread_s, gap);
      std::fflush(stdout);
    }
  }

  // Each map holds two sessions at its owner; one handed off or dropped holds none.
  std::printf("PostgreSQL sessions on the fleet's database: %d (%zu maps, 3 instances)\n",
              fleet.DatabaseSessions(), maps.size());
  for (auto& r : robots) r->Stop();
  bool exact = true;
  for (auto& r : robots) {
    const grpc::Status s = r->client().Finish(std::chrono::seconds(60));
    const mapd::robot::IngestCounts c = r->client().counts();
    if (!s.ok() || c.rejected != 0 || c.stored + c.duplicate != r->sent()) {
      std::printf(
          "%s: %s, sent %llu, stored %llu, duplicate %llu, rejected %llu\n", r->map().c_str(),
          s.error_message().c_str(), static_cast<unsigned long long>(r->sent()),
          static_cast<unsigned long long>(c.stored), static_cast<unsigned long long>(c.duplicate),
          static_cast<unsigned long long>(c.rejected));
      exact = false;
    }
    const auto stored = fleet.StoredBatches(r->map());
    if (stored.size() != 1 || stored[0].second != r->sent()) {
      std::printf("%s: stored %llu batches, sent %llu\n", r->map().c_str(),
                  stored.size() == 1 ? static_cast<unsigned long long>(stored[0].second) : 0ull,
                  static_cast<unsigned long long>(r->sent()));
      exact = false;
    }
  }
  std::printf(
      "\n%d kills, %zu map takeovers: acknowledged again after p50 %.2f s, p90 %.2f s, max "
      "%.2f s\nhandback after each restart: longest ack pause p50 %.2f s, max %.2f s\n"
      "%zu graceful restarts (SIGTERM, %s): longest ack pause p50 %.2f s, max %.2f s\n"
      "every batch stored exactly once, none refused: %s\n",
      kills, takeover_s.size(), Percentile(takeover_s, 0.5), Percentile(takeover_s, 0.9),
      Percentile(takeover_s, 1.0), Percentile(handback_gap_s, 0.5), Percentile(handback_gap_s, 1.0),
      rolling_gap_s.size(), clean_stops ? "all exited 0" : "NOT ALL EXITED 0",
      Percentile(rolling_gap_s, 0.5), Percentile(rolling_gap_s, 1.0), exact ? "yes" : "NO");
  for (const MapdProcess& m : fleet.mapd) mapd::testing::Stop(m.pid, SIGTERM);
  return exact && clean_stops ? 0 : 1;
}
