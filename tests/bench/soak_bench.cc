// Long-running soak: N simulated robots loop the same building against a real
// mapd until `--total` raw features are stored, reporting every `--every`:
// ingest batches/s, fusion features/s (wall and per CPU-second of the fuser
// thread), fusion backlog, p99 ack latency, mapd's RSS, database bytes. At the
// `--restart-at` marks it stops the robots, waits for the fuser, records the
// map, SIGKILLs mapd, restarts it and measures the time to SERVING (GetStats
// says recovering = false) and to the full map (same map_version), and checks
// that the map is identical. At the end a robot that streamed in its own frame
// all along is tied to the map frame by an accepted submap merge, and the tie
// is timed (the `tied_sessions_fused` log line).
//
//   soak_bench [--world floor|city] [--robots 8] [--total 10000000]
//              [--every 1000000] [--restart-at 1000000,5000000,10000000]
//              [--mapd PATH] [--mapd-arg ARG]... [--keep DIR]
//
// Run on demand (docs/long-running.md); never by ctest.
#include <grpcpp/grpcpp.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <random>
#include <sstream>
#include <string>
#include <thread>
#include <unordered_map>
#include <vector>

#include "client/sim_robot.h"
#include "common/octomap_scenes.h"
#include "common/process.h"
#include "common/temp_dir.h"
#include "mapserver/v1/map_service.grpc.pb.h"
#include "sim/city_scenario.h"

namespace {

namespace pb = mapserver::v1;
namespace sc = mapd::fusion::scenario;
using Clock = std::chrono::steady_clock;

struct Options {
  std::string world = "floor";
  int robots = 8;
  uint64_t total = 10'000'000;
  uint64_t every = 1'000'000;
  std::vector<uint64_t> restart_at = {1'000'000, 5'000'000, 10'000'000};
  std::string mapd = MAPD_BINARY;
  std::string keep;                    // keep the database here instead of a temporary directory
  std::vector<std::string> mapd_args;  // --mapd-arg, repeated
};

double Seconds(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

// --- Batches. A pool per robot, replayed in loops with a fresh seq and a
// centimetre of pose jitter per send, so that no two laps are identical.

std::vector<pb::ObservationBatch> FloorPool(int robot, int robots, bool local) {
  mapd::client::SimRobotParams p;
  p.robot_id = (local ? "late-" : "r") + std::to_string(robot);
  p.session_id = local ? "own-frame" : "map";
  p.seed = static_cast<uint64_t>(robot) + 1;
  p.start_fraction = static_cast<double>(robot) / robots;
  mapd::client::SimRobot sim(mapd::client::DefaultWorld(), p);
  std::vector<pb::ObservationBatch> pool;
  for (int k = 0; k < 2000; ++k) {  // ~8 loops of the floor
    pb::ObservationBatch b = sim.NextBatch();
    if (local) {
      // Its own frame: the map frame turned a quarter and shifted, as the
      // submap merge at the end will find (the room scenes' T_map_b).
      b.set_session_frame(pb::SESSION_FRAME_LOCAL);
    }
    pool.push_back(std::move(b));
  }
  return pool;
}

std::vector<pb::ObservationBatch> CityPool(int robot, int robots, bool local) {
  sc::ScenarioParams params;
  params.seed = 1;
  params.blocks_x = 4;
  params.blocks_y = 3;
  static const sc::World world = sc::GenerateWorld(params);
  const sc::ScanSimulator sim(params, world);
  std::vector<pb::ObservationBatch> pool;
  const size_t n = sim.size();
  for (size_t k = 0; k < n; ++k) {
    const size_t index = (k + static_cast<size_t>(robot) * n / static_cast<size_t>(robots)) % n;
    const sc::Scan scan = sim.Simulate(index);
    pb::ObservationBatch b;
    b.set_robot_id((local ? "late-" : "r") + std::to_string(robot));
    b.set_session_id(local ? "own-frame" : "map");
    if (local) b.set_session_frame(pb::SESSION_FRAME_LOCAL);
    // The sensor where the scan was taken (its estimated position), the lines
    // relative to it: mapd's free-space evidence runs from the sensor to each
    // line, as it does for a real robot. (Before 2026-12-04 every batch put
    // the sensor at the map origin, so each visibility triangle ran up to
    // 270 m across the city: wrong evidence and a worst case for its cost.)
    const mapd::geometry::Vec2 sensor = scan.estimated_pose.t;
    b.mutable_t_frame_sensor()->mutable_rotation()->set_w(1.0);
    b.mutable_t_frame_sensor()->mutable_translation()->set_x(sensor.x());
    b.mutable_t_frame_sensor()->mutable_translation()->set_y(sensor.y());
    for (const mapd::fusion::GroundFeature& f : scan.features) {  // map frame
      pb::LineSegment* line = b.add_lines();
      line->mutable_a()->set_x(f.segment.a.x() - sensor.x());
      line->mutable_a()->set_y(f.segment.a.y() - sensor.y());
      line->mutable_b()->set_x(f.segment.b.x() - sensor.x());
      line->mutable_b()->set_y(f.segment.b.y() - sensor.y());
    }
    if (b.lines_size() > 0) pool.push_back(std::move(b));
  }
  return pool;
}

// --- Robots.

struct Shared {
  int robots = 0;  // at full rate
  std::atomic<bool> stop{false};
  std::atomic<uint64_t> acked_batches{0};
  std::atomic<uint64_t> rejected{0};
  std::mutex mu;
  std::vector<double> latencies_ms;  // this report window
};

struct Robot {
  std::vector<pb::ObservationBatch> pool;
  uint64_t next_seq = 1;
  int every_nth = 1;  // sends one batch per this many of the others' (the late robot: fewer)
  std::mt19937_64 rng;
};

// Streams until shared.stop; returns when every sent batch is acknowledged.
void RunRobot(const std::string& address, Robot* robot, Shared* shared) {
  auto stub =
      pb::MapService::NewStub(grpc::CreateChannel(address, grpc::InsecureChannelCredentials()));
  grpc::ClientContext ctx;
  auto stream = stub->Ingest(&ctx);
  std::mutex mu;
  std::condition_variable cv;
  int in_flight = 0;
  constexpr int kWindow = 256;
  std::unordered_map<uint64_t, Clock::time_point> sent;
  std::thread reader([&] {
    pb::IngestAck ack;
    std::vector<double> mine;
    while (stream->Read(&ack)) {
      Clock::time_point t0;
      {
        std::lock_guard<std::mutex> lock(mu);
        t0 = sent[ack.seq()];
        sent.erase(ack.seq());
        --in_flight;
      }
      cv.notify_one();
      mine.push_back(std::chrono::duration<double, std::milli>(Clock::now() - t0).count());
      if (ack.result() == pb::IngestAck::REJECTED) ++shared->rejected;
      ++shared->acked_batches;
      if (mine.size() >= 256) {
        std::lock_guard<std::mutex> lock(shared->mu);
        shared->latencies_ms.insert(shared->latencies_ms.end(), mine.begin(), mine.end());
        mine.clear();
      }
    }
    std::lock_guard<std::mutex> lock(shared->mu);
    shared->latencies_ms.insert(shared->latencies_ms.end(), mine.begin(), mine.end());
  });
  std::normal_distribution<double> jitter(0.0, 0.01);
  uint64_t last_paced = shared->acked_batches.load();
  while (!shared->stop.load()) {
    if (robot->every_nth > 1) {
      // A slower robot: one batch per every_nth of each full-rate robot's.
      const uint64_t step = static_cast<uint64_t>(robot->every_nth * shared->robots);
      while (!shared->stop.load() && shared->acked_batches.load() < last_paced + step) {
        std::this_thread::sleep_for(std::chrono::milliseconds(1));
      }
      last_paced = shared->acked_batches.load();
      if (shared->stop.load()) break;
    }
    pb::ObservationBatch b = robot->pool[(robot->next_seq - 1) % robot->pool.size()];
    b.set_seq(robot->next_seq);
    auto* t = b.mutable_t_frame_sensor()->mutable_translation();
    t->set_x(t->x() + jitter(robot->rng));
    t->set_y(t->y() + jitter(robot->rng));
    {
      std::unique_lock<std::mutex> lock(mu);
      cv.wait(lock, [&] { return in_flight < kWindow; });
      ++in_flight;
      sent[robot->next_seq] = Clock::now();
    }
    if (!stream->Write(b)) break;
    ++robot->next_seq;
  }
  stream->WritesDone();
  reader.join();
  (void)stream->Finish();
}

// --- The server.

// "snapshot, replayed N in T ms" from mapd's map_recovered log line.
std::string RecoveredFrom(const std::string& log) {
  const size_t at = log.find("event=map_recovered");
  if (at == std::string::npos) return "?";
  const std::string line = log.substr(at, log.find('\n', at) - at);
  const auto field = [&](const std::string& key) {
    const size_t k = line.find(" " + key + "=");
    if (k == std::string::npos) return std::string("?");
    const size_t v = k + key.size() + 2;
    return line.substr(v, line.find(' ', v) - v);
  };
  return field("from") + ", replayed " + field("replayed") + " in " + field("ms") + " ms";
}

pb::Stats GetStats(pb::MapService::Stub* stub) {
  grpc::ClientContext ctx;
  ctx.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(60));
  pb::Stats stats;
  if (!stub->GetStats(&ctx, {}, &stats).ok()) stats.set_recovering(true);
  return stats;
}

struct MapSnapshot {
  uint64_t version = 0;
  std::vector<std::string> features;  // serialised, in order
  bool ok = false;
};

MapSnapshot GetMap(pb::MapService::Stub* stub) {
  grpc::ClientContext ctx;
  auto reader = stub->GetFeatureMap(&ctx, {});
  MapSnapshot m;
  pb::FeatureMapPage page;
  while (reader->Read(&page)) {
    m.version = page.map_version();
    for (const pb::FusedFeature& f : page.features()) m.features.push_back(f.SerializeAsString());
  }
  m.ok = reader->Finish().ok();
  return m;
}

// CPU seconds of mapd's thread named `name` (MapCore names its threads).
double ThreadCpuSeconds(pid_t pid, const std::string& name) {
  const std::string dir = "/proc/" + std::to_string(pid) + "/task";
  std::error_code ec;
  for (const auto& task : std::filesystem::directory_iterator(dir, ec)) {
    std::ifstream comm(task.path() / "comm");
    std::string c;
    std::getline(comm, c);
    if (c != name) continue;
    return mapd::testing::CpuSecondsInStat((task.path() / "stat").string());
  }
  return 0;
}

double Quantile(std::vector<double> v, double q) {
  if (v.empty()) return 0;
  const size_t k = std::min(v.size() - 1, static_cast<size_t>(q * static_cast<double>(v.size())));
  std::nth_element(v.begin(), v.begin() + static_cast<long>(k), v.end());
  return v[k];
}

double P99(std::vector<double> v) { return Quantile(std::move(v), 0.99); }

// Appends the encode_ms of every "event=snapshot_written" line of a mapd log
// (the fuser's stall per snapshot; a restart truncates the log, so read it
// before each).
void CollectSnapshotEncodes(const std::string& log, std::vector<double>* encode_ms) {
  std::istringstream lines(log);
  for (std::string line; std::getline(lines, line);) {
    if (line.find("event=snapshot_written") == std::string::npos) continue;
    const size_t at = line.find("encode_ms=");
    if (at != std::string::npos) encode_ms->push_back(std::atof(line.c_str() + at + 10));
  }
}

// --- The tie at the end: two views of a room as submaps, one per robot.

double TieLateRobot(pb::MapService::Stub* stub, const std::string& mapd_log,
                    const std::string& late) {
  mapd::testing::RoomScene scene;
  const std::string west = mapd::testing::RoomSubmap(scene, 0, 8, Eigen::Isometry3d::Identity());
  const std::string east = mapd::testing::RoomSubmap(
      scene, 2, 10, mapd::testing::YawTranslation(M_PI / 2, Eigen::Vector3d(2.0, -1.0, 0.0)));
  uint64_t ids[2] = {0, 0};
  const std::string robots[2] = {"r0", late};
  const std::string sessions[2] = {"map", "own-frame"};
  const std::string* files[2] = {&west, &east};
  for (int i = 0; i < 2; ++i) {
    grpc::ClientContext ctx;
    pb::SubmapInfo info;
    auto writer = stub->UploadSubmap(&ctx, &info);
    pb::UploadSubmapRequest header;
    header.mutable_header()->set_robot_id(robots[i]);
    header.mutable_header()->set_name("soak-room");
    header.mutable_header()->set_session_id(sessions[i]);
    header.mutable_header()->set_resolution(0.0);
    header.mutable_header()->set_format(pb::SUBMAP_FORMAT_OCTOMAP_BT);
    writer->Write(header);
    pb::UploadSubmapRequest chunk;
    chunk.set_chunk(*files[i]);
    writer->Write(chunk);
    writer->WritesDone();
    const grpc::Status s = writer->Finish();
    if (!s.ok()) {
      std::printf("tie: upload failed: %s\n", s.error_message().c_str());
      return -1;
    }
    ids[i] = info.id();
  }
  const auto t0 = Clock::now();
  grpc::ClientContext ctx;
  pb::MergeSubmapsRequest request;
  request.add_submap_ids(ids[0]);
  request.add_submap_ids(ids[1]);
  auto reader = stub->MergeSubmaps(&ctx, request);
  pb::MergeProgress p;
  while (reader->Read(&p)) {
  }
  const grpc::Status s = reader->Finish();
  if (!s.ok()) {
    std::printf("tie: merge refused: %s\n", s.error_message().c_str());
    return -1;
  }
  // The fuser logs the tie once it has fused the session's stored observations.
  for (int i = 0; i < 600; ++i) {
    const std::string log = mapd::testing::internal::ReadFile(mapd_log);
    const size_t at = log.rfind("event=tied_sessions_fused");
    if (at != std::string::npos) {
      const std::string line = log.substr(at, log.find('\n', at) - at);
      std::printf("tie: merge RPC %.2f s; %s\n", Seconds(t0), line.c_str());
      const size_t ms = line.find("ms=");
      return ms == std::string::npos ? -1 : std::stod(line.substr(ms + 3)) / 1000.0;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  return -1;
}

}  // namespace

int main(int argc, char** argv) {
  Options opt;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    const bool v = i + 1 < argc;
    if (a == "--world" && v)
      opt.world = argv[++i];
    else if (a == "--robots" && v)
      opt.robots = std::atoi(argv[++i]);
    else if (a == "--total" && v)
      opt.total = std::strtoull(argv[++i], nullptr, 10);
    else if (a == "--every" && v)
      opt.every = std::strtoull(argv[++i], nullptr, 10);
    else if (a == "--mapd" && v)
      opt.mapd = argv[++i];
    else if (a == "--keep" && v)
      opt.keep = argv[++i];
    else if (a == "--mapd-arg" && v)
      opt.mapd_args.push_back(argv[++i]);
    else if (a == "--restart-at" && v) {
      opt.restart_at.clear();
      std::stringstream list(argv[++i]);
      for (std::string item; std::getline(list, item, ',');)
        opt.restart_at.push_back(std::stoull(item));
    } else {
      std::fprintf(stderr,
                   "usage: %s [--world floor|city] [--robots N] [--total N] [--every N] "
                   "[--restart-at A,B,..] [--mapd PATH] [--mapd-arg ARG]... [--keep DIR]\n",
                   argv[0]);
      return 2;
    }
  }
  if (opt.world != "floor" && opt.world != "city") {
    std::fprintf(stderr, "--world is floor or city\n");
    return 2;
  }
  mapd::testing::TempDir tmp;
  const std::string dir = opt.keep.empty() ? tmp.path() : opt.keep;
  const std::string db = dir + "/soak.db";

  std::vector<Robot> robots(static_cast<size_t>(opt.robots) + 1);
  for (int r = 0; r <= opt.robots; ++r) {
    const bool late = r == opt.robots;  // the robot in its own frame, tied at the end
    Robot& robot = robots[static_cast<size_t>(r)];
    robot.pool =
        opt.world == "floor" ? FloorPool(r, opt.robots, late) : CityPool(r, opt.robots, late);
    robot.rng.seed(static_cast<uint64_t>(r) + 77);
    robot.every_nth = late ? 4 : 1;
  }
  const std::string late_name = robots.back().pool.front().robot_id();

  mapd::testing::MapdProcess mapd = mapd::testing::StartMapd(db, opt.mapd_args, opt.mapd);
  if (mapd.port == 0) {
    std::fprintf(stderr, "mapd did not start\n%s", mapd.log().c_str());
    return 1;
  }
  auto stub = pb::MapService::NewStub(
      grpc::CreateChannel(mapd.address, grpc::InsecureChannelCredentials()));
  std::printf("world %s, %d robots + 1 in its own frame (streams a quarter as often), mapd %s\n\n",
              opt.world.c_str(), opt.robots, mapd.address.c_str());
  std::printf(
      "| raw features | ingest batches/s | fused features/s (wall) | fused features/CPU-s "
      "(fuser) | fusion nodes | backlog | p99 ack ms | mapd RSS MiB | db MiB | db bytes/feature |\n"
      "|---|---|---|---|---|---|---|---|---|---|\n");

  Shared shared;
  shared.robots = opt.robots;
  std::vector<std::thread> threads;
  const auto start_robots = [&] {
    shared.stop = false;
    for (Robot& r : robots) threads.emplace_back(RunRobot, mapd.address, &r, &shared);
  };
  const auto stop_robots = [&] {
    shared.stop = true;
    for (std::thread& t : threads) t.join();
    threads.clear();
  };
  start_robots();
  const auto soak_start = Clock::now();
  uint64_t next_report = opt.every;
  size_t next_restart = 0;
  auto window_t = Clock::now();
  uint64_t window_batches = 0, window_fused = 0;
  double window_cpu = ThreadCpuSeconds(mapd.pid, "mapd-fuser");
  std::vector<std::string> restarts;
  std::vector<double> encode_ms;  // snapshot_written's, of every mapd before a restart
  for (;;) {
    std::this_thread::sleep_for(std::chrono::milliseconds(200));
    const pb::Stats stats = GetStats(stub.get());
    const uint64_t raw = stats.raw_features();
    if (raw >= next_report || raw >= opt.total) {
      const double dt = Seconds(window_t);
      const double cpu = ThreadCpuSeconds(mapd.pid, "mapd-fuser");
      const uint64_t batches = shared.acked_batches.load();
      std::vector<double> latencies;
      {
        std::lock_guard<std::mutex> lock(shared.mu);
        latencies.swap(shared.latencies_ms);
      }
      std::printf("| %.2fM | %.0f | %.0f | %.0f | %llu | %llu | %.1f | %.0f | %.0f | %.0f |\n",
                  raw / 1e6, static_cast<double>(batches - window_batches) / dt,
                  static_cast<double>(stats.fused_raw_features() - window_fused) / dt,
                  static_cast<double>(stats.fused_raw_features() - window_fused) /
                      std::max(1e-9, cpu - window_cpu),
                  static_cast<unsigned long long>(stats.fusion_nodes()),
                  static_cast<unsigned long long>(stats.fusion_backlog()), P99(latencies),
                  mapd::testing::ResidentMiB(mapd.pid), stats.db_size_bytes() / 1048576.0,
                  stats.bytes_per_raw_feature());
      std::fflush(stdout);
      window_t = Clock::now();
      window_batches = batches;
      window_fused = stats.fused_raw_features();
      window_cpu = cpu;
      while (next_report <= raw) next_report += opt.every;
    }
    const bool restart_due =
        next_restart < opt.restart_at.size() && raw >= opt.restart_at[next_restart];
    if (!restart_due && raw < opt.total) continue;

    // Quiesce: robots stop, every ack in, the fuser catches up.
    stop_robots();
    pb::Stats quiet = GetStats(stub.get());
    while (quiet.fusion_backlog() > 0) {
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
      quiet = GetStats(stub.get());
    }
    const MapSnapshot before = GetMap(stub.get());
    if (restart_due) {
      ++next_restart;
      CollectSnapshotEncodes(mapd.log(), &encode_ms);
      mapd::testing::Stop(mapd.pid, SIGKILL);
      const auto t0 = Clock::now();
      // Back as soon as it listens (it recovers the map after that).
      mapd = mapd::testing::StartMapd(db, opt.mapd_args, opt.mapd, std::chrono::seconds(120),
                                      "listening");
      const std::string address = mapd.address;
      stub =
          pb::MapService::NewStub(grpc::CreateChannel(address, grpc::InsecureChannelCredentials()));
      double serving_s = -1, full_s = -1;
      while (Seconds(t0) < 600) {
        if (serving_s < 0 && !GetStats(stub.get()).recovering()) serving_s = Seconds(t0);
        if (serving_s >= 0) {
          const MapSnapshot after = GetMap(stub.get());
          if (after.ok && after.version >= before.version) {
            full_s = Seconds(t0);
            // The recovery's summary line follows the replay's last round.
            for (int i = 0; i < 200 && mapd.log().find("event=map_recovered") == std::string::npos;
                 ++i) {
              std::this_thread::sleep_for(std::chrono::milliseconds(5));
            }
            char line[512];
            std::snprintf(line, sizeof(line),
                          "| %.2fM | %.3f | %.3f | %s (%zu features, map_version %llu) | %s |",
                          raw / 1e6, serving_s, full_s,
                          after.features == before.features ? "identical" : "DIFFERENT",
                          after.features.size(), static_cast<unsigned long long>(after.version),
                          RecoveredFrom(mapd.log()).c_str());
            restarts.push_back(line);
            break;
          }
        }
        std::this_thread::sleep_for(std::chrono::milliseconds(5));
      }
      window_cpu = ThreadCpuSeconds(mapd.pid, "mapd-fuser");
      window_t = Clock::now();
      window_fused = GetStats(stub.get()).fused_raw_features();
    }
    if (raw >= opt.total) break;
    start_robots();
  }
  const pb::Stats end_stats = GetStats(stub.get());
  if (next_restart == 0 || opt.restart_at[next_restart - 1] < opt.total)
    CollectSnapshotEncodes(mapd.log(), &encode_ms);
  std::printf(
      "\nsoak: %.0f s to %.2fM raw features, %llu batches rejected; %llu fused features, %llu "
      "retired walls (a static world: should be 0)\n",
      Seconds(soak_start), end_stats.raw_features() / 1e6,
      static_cast<unsigned long long>(shared.rejected.load()),
      static_cast<unsigned long long>(end_stats.fused_features()),
      static_cast<unsigned long long>(end_stats.retired_walls()));
  std::printf(
      "\nRestarts (SIGKILL, then restart on the same database):\n\n"
      "| raw features | to SERVING (s) | to the full map (s) | map after vs before | "
      "recovered from |\n"
      "|---|---|---|---|---|\n");
  for (const std::string& r : restarts) std::printf("%s\n", r.c_str());
  std::printf(
      "\nsnapshots taken while streaming: %zu, encoding on the fuser thread median %.0f ms, "
      "p90 %.0f ms, max %.0f ms\n\n",
      encode_ms.size(), Quantile(encode_ms, 0.5), Quantile(encode_ms, 0.9),
      Quantile(encode_ms, 1.0));
  const double tie_s = TieLateRobot(stub.get(), mapd.log_path, late_name);
  std::printf("tie of %s's session with %.2fM raw features stored: %.2f s\n", late_name.c_str(),
              GetStats(stub.get()).raw_features() / 1e6, tie_s);
  mapd::testing::Stop(mapd.pid, SIGTERM);
  return 0;
}
