// A fleet on several mapd (docs/scale-out.md, "A fleet, measured"): by
// default 50 maps x 2 robots on 3 instances sharing one PostgreSQL (fsync
// on) for 10 minutes, each robot streaming a simulated batch every 200 ms
// with RobotClient (half of them started at an instance that does not serve
// their map, so redirects are exercised). Every 10 s: each instance's RSS
// and CPU. At the end: RSS per map served, CPU per instance, the snapshots'
// size per map, then one instance stopped with SIGTERM and how long its maps
// took to load on the others; every batch must be stored exactly once.
//
//   fleet_soak_bench [--seconds 600] [--maps 50] [--robots_per_map 2]
//                    [--period_ms 200] [--instances 3]
#include <libpq-fe.h>
#include <signal.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <map>
#include <memory>
#include <numeric>
#include <regex>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "client/support/fleet.h"
#include "client/support/streaming_robot.h"

namespace {

using Clock = std::chrono::steady_clock;
using mapd::testing::Fleet;
using mapd::testing::StreamingRobot;

double Percentile(std::vector<double> v, double p) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  return v[static_cast<size_t>(p * static_cast<double>(v.size() - 1) + 0.5)];
}

// Resident memory, MiB.
double RssMiB(pid_t pid) {
  std::ifstream status("/proc/" + std::to_string(pid) + "/status");
  for (std::string line; std::getline(status, line);) {
    if (line.rfind("VmRSS:", 0) == 0) return std::atof(line.c_str() + 6) / 1024.0;
  }
  return 0;
}

// User + system CPU time, seconds.
double CpuSeconds(pid_t pid) {
  std::ifstream stat("/proc/" + std::to_string(pid) + "/stat");
  std::string text((std::istreambuf_iterator<char>(stat)), std::istreambuf_iterator<char>());
  const size_t close = text.rfind(')');
  if (close == std::string::npos) return 0;
  std::istringstream fields(text.substr(close + 2));
  std::string field;
  double utime = 0, stime = 0;
  for (int i = 3; fields >> field; ++i) {  // field 3 is the state
    if (i == 14) utime = std::atof(field.c_str());
    if (i == 15) {
      stime = std::atof(field.c_str());
      break;
    }
  }
  return (utime + stime) / static_cast<double>(sysconf(_SC_CLK_TCK));
}

// The machine's busy share of its CPU time since the last call.
class MachineLoad {
 public:
  double Busy() {
    std::ifstream stat("/proc/stat");
    std::string cpu;
    double v[8] = {};
    stat >> cpu;
    for (double& x : v) stat >> x;
    const double idle = v[3] + v[4], total = v[0] + v[1] + v[2] + v[3] + v[4] + v[5] + v[6] + v[7];
    const double busy = total > total_ ? 1.0 - (idle - idle_) / (total - total_) : 0;
    idle_ = idle;
    total_ = total;
    return busy;
  }

 private:
  double idle_ = 0, total_ = 0;
};

// Each map's newest snapshot, bytes of fusion state.
std::map<std::string, double> SnapshotBytes(const std::string& conninfo) {
  std::map<std::string, double> bytes;
  PGconn* conn = PQconnectdb(conninfo.c_str());
  PGresult* r = PQexec(conn,
                       "SELECT DISTINCT ON (map) map, coalesce(state_bytes, octet_length(state)) + "
                       "coalesce(octet_length(plane_state), 0) FROM fusion_snapshots "
                       "ORDER BY map, id DESC");
  if (PQresultStatus(r) == PGRES_TUPLES_OK) {
    for (int i = 0; i < PQntuples(r); ++i)
      bytes[PQgetvalue(r, i, 0)] = std::atof(PQgetvalue(r, i, 1));
  } else {
    std::fprintf(stderr, "snapshots: %s\n", PQerrorMessage(conn));
  }
  PQclear(r);
  PQfinish(conn);
  return bytes;
}

// The `event=map_recovered` lines of a log after byte `from`: milliseconds each.
std::vector<double> RecoveryMs(const std::string& log, size_t from, std::vector<std::string>* how) {
  static const std::regex kLine(R"(event=map_recovered from=(\S+).* ms=(\d+))");
  std::vector<double> ms;
  std::istringstream in(log.substr(std::min(from, log.size())));
  for (std::string line; std::getline(in, line);) {
    std::smatch m;
    if (std::regex_search(line, m, kLine)) {
      how->push_back(m[1]);
      ms.push_back(std::atof(m[2].str().c_str()));
    }
  }
  return ms;
}

}  // namespace

int main(int argc, char** argv) {
  int seconds = 600, n_maps = 50, per_map = 2, period_ms = 200, instances = 3;
  for (int i = 1; i + 1 < argc; i += 2) {
    if (!std::strcmp(argv[i], "--seconds")) seconds = std::atoi(argv[i + 1]);
    if (!std::strcmp(argv[i], "--maps")) n_maps = std::atoi(argv[i + 1]);
    if (!std::strcmp(argv[i], "--robots_per_map")) per_map = std::atoi(argv[i + 1]);
    if (!std::strcmp(argv[i], "--period_ms")) period_ms = std::atoi(argv[i + 1]);
    if (!std::strcmp(argv[i], "--instances")) instances = std::atoi(argv[i + 1]);
  }
  Fleet fleet;
  if (!fleet.StartDatabase()) return 1;
  if (!fleet.Launch(instances)) return 1;
  std::vector<double> idle_rss;
  for (const auto& m : fleet.mapd) idle_rss.push_back(RssMiB(m.pid));
  const std::vector<std::string> maps = fleet.CreateMaps(n_maps);
  if (maps.empty()) return 1;
  const double spread_s = fleet.WaitSpread(maps, 300);
  if (spread_s < 0) {
    std::fprintf(stderr, "the maps did not spread over the instances\n");
    return 1;
  }
  std::printf("%d instances, %d maps spread after %.1f s; idle RSS", instances, n_maps, spread_s);
  for (double r : idle_rss) std::printf(" %.0f", r);
  std::printf(" MiB\n");

  std::vector<std::unique_ptr<StreamingRobot>> robots;
  std::vector<std::string> robot_ids;
  for (size_t m = 0; m < maps.size(); ++m) {
    for (int r = 0; r < per_map; ++r) {
      robot_ids.push_back("robot-" + maps[m] + "-" + std::to_string(r));
      std::vector<std::string> addresses = fleet.addresses;  // each starts elsewhere
      std::rotate(addresses.begin(), addresses.begin() + (m + r) % addresses.size(),
                  addresses.end());
      robots.push_back(std::make_unique<StreamingRobot>(maps[m], addresses, robot_ids.back(),
                                                        std::chrono::milliseconds(period_ms)));
    }
  }
  MachineLoad load;
  load.Busy();
  std::vector<double> cpu_start;
  for (const auto& m : fleet.mapd) cpu_start.push_back(CpuSeconds(m.pid));
  const auto start = Clock::now();
  auto acked = [&] {
    uint64_t n = 0;
    for (const auto& r : robots) n += r->acked();
    return n;
  };
  const uint64_t acked_start = acked();
  std::vector<double> busy;
  for (int t = 10; t <= seconds; t += 10) {
    std::this_thread::sleep_until(start + std::chrono::seconds(t));
    busy.push_back(load.Busy());
    std::printf("t=%3d s: acked %llu, machine busy %.0f%%, RSS", t,
                static_cast<unsigned long long>(acked() - acked_start), 100 * busy.back());
    for (const auto& m : fleet.mapd) std::printf(" %.0f", RssMiB(m.pid));
    std::printf(" MiB, CPU");
    for (size_t i = 0; i < fleet.mapd.size(); ++i) {
      std::printf(" %.1f", CpuSeconds(fleet.mapd[i].pid) - cpu_start[i]);
    }
    std::printf(" s\n");
    std::fflush(stdout);
  }
  const double run_s = std::chrono::duration<double>(Clock::now() - start).count();
  const uint64_t acked_run = acked() - acked_start;

  std::map<std::string, int> served;  // address -> maps
  for (const std::string& map : maps) ++served[fleet.Owner(map)];
  std::printf(
      "\nafter %.0f s: %llu batches acknowledged (%.0f/s), machine busy %.0f%% on average\n", run_s,
      static_cast<unsigned long long>(acked_run), acked_run / run_s,
      100 * std::accumulate(busy.begin(), busy.end(), 0.0) / std::max<size_t>(busy.size(), 1));
  for (size_t i = 0; i < fleet.mapd.size(); ++i) {
    const int n = served[fleet.addresses[i]];
    const double rss = RssMiB(fleet.mapd[i].pid);
    std::printf("%s: %d maps, RSS %.0f MiB (%.1f MiB per map over idle), CPU %.0f%% of a core\n",
                fleet.names[i].c_str(), n, rss, n > 0 ? (rss - idle_rss[i]) / n : 0.0,
                100 * (CpuSeconds(fleet.mapd[i].pid) - cpu_start[i]) / run_s);
  }
  std::vector<double> snapshot_kib;
  for (const auto& [map, bytes] : SnapshotBytes(fleet.store)) snapshot_kib.push_back(bytes / 1024);
  std::printf("snapshots: %zu maps have one, newest per map p50 %.0f KiB, max %.0f KiB\n",
              snapshot_kib.size(), Percentile(snapshot_kib, 0.5), Percentile(snapshot_kib, 1.0));

  // One instance leaves gracefully: its maps load on the others.
  std::vector<size_t> log_sizes;
  for (const auto& m : fleet.mapd) log_sizes.push_back(m.log().size());
  const int leaving = 0;
  const int code = mapd::testing::Stop(fleet.mapd[leaving].pid, SIGTERM, std::chrono::seconds(60));
  std::vector<std::string> rest_names, rest_addresses;
  for (int i = 0; i < instances; ++i) {
    if (i == leaving) continue;
    rest_names.push_back(fleet.names[i]);
    rest_addresses.push_back(fleet.addresses[i]);
  }
  Fleet rest;  // the instances left, to wait for the maps to spread over them
  rest.names = rest_names;
  rest.addresses = rest_addresses;
  const double moved_s = rest.WaitSpread(maps, 120);
  std::vector<double> load_ms;
  std::vector<std::string> load_from;
  for (int i = 0; i < instances; ++i) {
    if (i == leaving) continue;
    for (double ms : RecoveryMs(fleet.mapd[i].log(), log_sizes[i], &load_from)) {
      load_ms.push_back(ms);
    }
  }
  const auto from_snapshot = std::count(load_from.begin(), load_from.end(), "snapshot");
  std::printf(
      "%s stopped (SIGTERM, exit %d): its %d maps served elsewhere after %.1f s; %zu loaded "
      "(%ld from a snapshot) in p50 %.0f ms, max %.0f ms\n",
      fleet.names[leaving].c_str(), code, served[fleet.addresses[leaving]], moved_s, load_ms.size(),
      static_cast<long>(from_snapshot), Percentile(load_ms, 0.5), Percentile(load_ms, 1.0));

  for (auto& r : robots) r->Stop();
  bool exact = true;
  for (auto& r : robots) {
    const grpc::Status s = r->client().Finish(std::chrono::seconds(120));
    const mapd::robot::IngestCounts c = r->client().counts();
    if (!s.ok() || c.rejected != 0 || c.stored + c.duplicate != r->sent()) exact = false;
  }
  for (const std::string& map : maps) {
    std::map<std::string, uint64_t> sent;  // robot -> batches, this map's
    for (size_t i = 0; i < robots.size(); ++i) {
      if (robots[i]->map() == map) sent[robot_ids[i]] = robots[i]->sent();
    }
    for (const auto& [robot, batches] : fleet.StoredBatches(map)) {
      if (sent[robot] != batches) {
        std::printf("%s %s: stored %llu, sent %llu\n", map.c_str(), robot.c_str(),
                    static_cast<unsigned long long>(batches),
                    static_cast<unsigned long long>(sent[robot]));
        exact = false;
      }
      sent.erase(robot);
    }
    if (!sent.empty()) exact = false;
  }
  std::printf("every batch stored exactly once, none refused: %s\n", exact ? "yes" : "NO");
  for (const auto& m : fleet.mapd) mapd::testing::Stop(m.pid, SIGTERM);
  return exact ? 0 : 1;
}
