// Ingest load generator: N concurrent simulated robots stream batches of
// ~20 line features to a real mapd process; reports acknowledged batches/s and
// features/s, ack latency percentiles and the server's RSS, next to SQLite's
// own commit ceiling measured in the same run on the same disk.
//
//   ingest_bench [--robots 16] [--batches 4000] [--features 20] [--window 256]
//                [--sync normal|full] [--mapd PATH] [--server HOST:PORT]
//
// Not a test: run it on demand (see docs/benchmarks.md).
#include <grpcpp/grpcpp.h>
#include <sqlite3.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <map>
#include <mutex>
#include <random>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "common/clock.h"
#include "common/process.h"
#include "common/temp_dir.h"
#include "mapserver/v1/map_service.grpc.pb.h"

namespace {

namespace pb = mapserver::v1;
using Clock = std::chrono::steady_clock;

struct Options {
  int robots = 16;
  int batches = 4000;  // per robot
  int features = 20;
  int window = 256;  // unacknowledged batches per robot
  std::string sync = "normal";
  std::string mapd = MAPD_BINARY;
  std::string server;  // use a running server instead of starting one
};

// A city block grid: walls on x = 10 k and y = 10 k within 400 m x 400 m.
// Each batch: `n` wall pieces 1-3 m long near the robot, 1 cm noise, sensor frame.
pb::ObservationBatch MakeBatch(std::mt19937_64& rng, const std::string& robot, int n) {
  std::uniform_real_distribution<double> pos(0, 400), len(1, 3), off(-8, 8), yaw(-M_PI, M_PI);
  std::normal_distribution<double> noise(0, 0.01);
  const double x = pos(rng), y = pos(rng), th = yaw(rng);
  const double c = std::cos(th), s = std::sin(th);
  pb::ObservationBatch b;
  b.set_robot_id(robot);
  b.set_session_id("bench");
  auto* T = b.mutable_t_frame_sensor();
  T->mutable_translation()->set_x(x);
  T->mutable_translation()->set_y(y);
  T->mutable_rotation()->set_w(std::cos(th / 2));
  T->mutable_rotation()->set_z(std::sin(th / 2));
  auto to_sensor = [&](double wx, double wy, pb::Vec3* out) {
    const double dx = wx - x, dy = wy - y;
    out->set_x(c * dx + s * dy);
    out->set_y(-s * dx + c * dy);
    out->set_z(0);
  };
  for (int i = 0; i < n; ++i) {
    const bool vertical = rng() & 1;
    const double along = (vertical ? y : x) + off(rng);
    const double wall = std::round(((vertical ? x : y) + off(rng)) / 10.0) * 10.0;
    const double l = len(rng);
    double ax, ay, bx, by;
    if (vertical) {
      ax = wall + noise(rng), ay = along, bx = wall + noise(rng), by = along + l;
    } else {
      ax = along, ay = wall + noise(rng), bx = along + l, by = wall + noise(rng);
    }
    auto* line = b.add_lines();
    to_sensor(ax, ay, line->mutable_a());
    to_sensor(bx, by, line->mutable_b());
  }
  return b;
}

struct RobotResult {
  std::vector<double> latencies_ms;
  int stored = 0, duplicate = 0, rejected = 0;
  std::string error;
};

void RunRobot(const std::shared_ptr<grpc::Channel>& channel, int index, const Options& opt,
              RobotResult* result) {
  auto stub = pb::MapService::NewStub(channel);
  std::mt19937_64 rng(1000 + static_cast<uint64_t>(index));
  const std::string robot = "robot-" + std::to_string(index);
  std::vector<pb::ObservationBatch> pool;
  for (int i = 0; i < 64; ++i) pool.push_back(MakeBatch(rng, robot, opt.features));

  grpc::ClientContext ctx;
  auto stream = stub->Ingest(&ctx);
  std::vector<int64_t> sent_ns(static_cast<size_t>(opt.batches) + 1, 0);
  std::mutex mu;
  std::condition_variable cv;
  int in_flight = 0;

  std::thread reader([&] {
    pb::IngestAck ack;
    result->latencies_ms.reserve(static_cast<size_t>(opt.batches));
    while (stream->Read(&ack)) {
      const int64_t now = mapd::SteadyNowNs();
      result->latencies_ms.push_back(static_cast<double>(now - sent_ns[ack.seq()]) / 1e6);
      switch (ack.result()) {
        case pb::IngestAck::STORED:
          ++result->stored;
          break;
        case pb::IngestAck::DUPLICATE:
          ++result->duplicate;
          break;
        default:
          if (result->rejected++ == 0) result->error = ack.message();
      }
      std::lock_guard<std::mutex> lock(mu);
      --in_flight;
      cv.notify_one();
    }
  });
  for (int seq = 1; seq <= opt.batches; ++seq) {
    pb::ObservationBatch& b = pool[static_cast<size_t>(seq) % pool.size()];
    b.set_seq(static_cast<uint64_t>(seq));
    {
      std::unique_lock<std::mutex> lock(mu);
      cv.wait(lock, [&] { return in_flight < opt.window; });
      ++in_flight;
    }
    sent_ns[static_cast<size_t>(seq)] = mapd::SteadyNowNs();
    if (!stream->Write(b)) break;
  }
  stream->WritesDone();
  reader.join();
  const grpc::Status s = stream->Finish();
  if (!s.ok()) result->error = s.error_message();
}

// SQLite's own ceiling on this disk: blobs of the batch's size, WAL, the given sync.
double SqliteRowsPerSecond(const std::string& path, const std::string& sync, int rows_per_commit,
                           size_t blob_bytes, double seconds) {
  sqlite3* db = nullptr;
  sqlite3_open(path.c_str(), &db);
  sqlite3_exec(db, "PRAGMA journal_mode=WAL", nullptr, nullptr, nullptr);
  sqlite3_exec(db, ("PRAGMA synchronous=" + sync).c_str(), nullptr, nullptr, nullptr);
  sqlite3_exec(db,
               "CREATE TABLE IF NOT EXISTS t (id INTEGER PRIMARY KEY, k INTEGER, s INTEGER, "
               "payload BLOB, UNIQUE (k, s))",
               nullptr, nullptr, nullptr);
  sqlite3_stmt* ins = nullptr;
  sqlite3_prepare_v2(db, "INSERT INTO t (k, s, payload) VALUES (?1, ?2, ?3)", -1, &ins, nullptr);
  const std::string blob(blob_bytes, 'x');
  const auto t0 = Clock::now();
  int64_t rows = 0;
  while (std::chrono::duration<double>(Clock::now() - t0).count() < seconds) {
    sqlite3_exec(db, "BEGIN", nullptr, nullptr, nullptr);
    for (int i = 0; i < rows_per_commit; ++i, ++rows) {
      sqlite3_bind_int64(ins, 1, rows % 16);
      sqlite3_bind_int64(ins, 2, rows);
      sqlite3_bind_blob(ins, 3, blob.data(), static_cast<int>(blob.size()), SQLITE_STATIC);
      sqlite3_step(ins);
      sqlite3_reset(ins);
    }
    sqlite3_exec(db, "COMMIT", nullptr, nullptr, nullptr);
  }
  const double dt = std::chrono::duration<double>(Clock::now() - t0).count();
  sqlite3_finalize(ins);
  sqlite3_close(db);
  return static_cast<double>(rows) / dt;
}

std::string ProcStatus(pid_t pid, const char* key) {
  std::ifstream in("/proc/" + std::to_string(pid) + "/status");
  std::string line;
  while (std::getline(in, line)) {
    if (line.rfind(key, 0) == 0) {
      std::istringstream s(line.substr(std::strlen(key) + 1));
      double kb = 0;
      s >> kb;
      char buf[32];
      std::snprintf(buf, sizeof(buf), "%.0f MiB", kb / 1024.0);
      return buf;
    }
  }
  return "?";
}

double Percentile(std::vector<double>& v, double p) {
  if (v.empty()) return 0;
  const size_t k = std::min(v.size() - 1, static_cast<size_t>(p * static_cast<double>(v.size())));
  std::nth_element(v.begin(), v.begin() + static_cast<long>(k), v.end());
  return v[k];
}

}  // namespace

int main(int argc, char** argv) {
  Options opt;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string k = argv[i], v = argv[i + 1];
    if (k == "--robots")
      opt.robots = std::stoi(v);
    else if (k == "--batches")
      opt.batches = std::stoi(v);
    else if (k == "--features")
      opt.features = std::stoi(v);
    else if (k == "--window")
      opt.window = std::stoi(v);
    else if (k == "--sync")
      opt.sync = v;
    else if (k == "--mapd")
      opt.mapd = v;
    else if (k == "--server")
      opt.server = v;
    else {
      std::fprintf(stderr, "ingest_bench: unknown flag %s\n", k.c_str());
      return 2;
    }
  }
  mapd::testing::TempDir dir;
  pid_t pid = 0;
  std::string address = opt.server;
  if (address.empty()) {
    const mapd::testing::MapdProcess mapd =
        mapd::testing::StartMapd(dir.File("map.db"), {"--sync", opt.sync}, opt.mapd);
    if (mapd.port == 0) {
      std::fprintf(stderr, "ingest_bench: mapd did not start:\n%s\n", mapd.log().c_str());
      return 1;
    }
    pid = mapd.pid;
    address = mapd.address;
  }
  grpc::ChannelArguments ch_args;
  ch_args.SetInt(GRPC_ARG_USE_LOCAL_SUBCHANNEL_POOL, 1);
  std::vector<std::shared_ptr<grpc::Channel>> channels;
  for (int i = 0; i < opt.robots; ++i) {
    // One connection per robot, as on a real fleet.
    grpc::ChannelArguments a = ch_args;
    a.SetInt("mapd.bench.robot", i);
    channels.push_back(grpc::CreateCustomChannel(address, grpc::InsecureChannelCredentials(), a));
  }
  const double cpu0 = pid ? mapd::testing::CpuSeconds(pid) : 0;
  std::vector<RobotResult> results(static_cast<size_t>(opt.robots));
  const auto t0 = Clock::now();
  std::vector<std::thread> threads;
  for (int i = 0; i < opt.robots; ++i) {
    threads.emplace_back(RunRobot, channels[static_cast<size_t>(i)], i, std::cref(opt),
                         &results[static_cast<size_t>(i)]);
  }
  for (auto& t : threads) t.join();
  const double seconds = std::chrono::duration<double>(Clock::now() - t0).count();
  const double server_cpu = pid ? mapd::testing::CpuSeconds(pid) - cpu0 : 0;

  // Acks wait for durability only; the fused map follows. Time the catch-up.
  auto stats_stub = pb::MapService::NewStub(channels[0]);
  pb::Stats stats;
  for (;;) {
    grpc::ClientContext ctx;
    const grpc::Status got = stats_stub->GetStats(&ctx, {}, &stats);
    if (!got.ok()) {
      std::fprintf(stderr, "GetStats failed while waiting for the fused map: %s\n",
                   got.error_message().c_str());
      break;
    }
    if (stats.fusion_backlog() == 0) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  const double fused_after = std::chrono::duration<double>(Clock::now() - t0).count();

  std::vector<double> lat;
  int stored = 0, rejected = 0, duplicate = 0;
  for (auto& r : results) {
    lat.insert(lat.end(), r.latencies_ms.begin(), r.latencies_ms.end());
    stored += r.stored;
    rejected += r.rejected;
    duplicate += r.duplicate;
    if (!r.error.empty()) std::fprintf(stderr, "robot error: %s\n", r.error.c_str());
  }
  std::printf(
      "group commit: %llu commits, %.1f batches per commit\n",
      static_cast<unsigned long long>(stats.commits()),
      stats.commits() ? static_cast<double>(stored) / static_cast<double>(stats.commits()) : 0.0);
  std::printf(
      "fused map: %llu fused features from %llu raw, caught up %.2f s after the last ack "
      "(fusion rate %.0f features/s)\n",
      static_cast<unsigned long long>(stats.fused_features()),
      static_cast<unsigned long long>(stats.raw_features()), fused_after - seconds,
      stored * static_cast<double>(opt.features) / fused_after);
  const std::string rss = pid ? ProcStatus(pid, "VmRSS:") : "?";
  const std::string hwm = pid ? ProcStatus(pid, "VmHWM:") : "?";
  std::printf("robots=%d batches/robot=%d features/batch=%d window=%d sync=%s\n", opt.robots,
              opt.batches, opt.features, opt.window, opt.sync.c_str());
  std::printf("acknowledged: %d stored, %d duplicate, %d rejected in %.2f s\n", stored, duplicate,
              rejected, seconds);
  std::printf("throughput: %.0f batches/s, %.0f features/s\n", stored / seconds,
              stored * static_cast<double>(opt.features) / seconds);
  const double p50 = Percentile(lat, 0.50), p99 = Percentile(lat, 0.99),
               pmax = Percentile(lat, 1.0);
  std::printf("ack latency: p50 %.2f ms, p99 %.2f ms, max %.2f ms\n", p50, p99, pmax);
  std::printf("server: RSS %s, peak RSS %s, CPU %.2f s (%.0f%% of one core)\n", rss.c_str(),
              hwm.c_str(), server_cpu, 100 * server_cpu / seconds);

  if (pid) std::printf("mapd exit status: %d\n", mapd::testing::Stop(pid, SIGTERM));
  // SQLite's own ceiling on the same disk, same sync mode, batch-sized blobs.
  const size_t blob = 12 + static_cast<size_t>(opt.features) * 48;
  const double one = SqliteRowsPerSecond(dir.File("ceiling1.db"), opt.sync, 1, blob, 2.0);
  const double thirty = SqliteRowsPerSecond(dir.File("ceiling30.db"), opt.sync, 30, blob, 2.0);
  const double big = SqliteRowsPerSecond(dir.File("ceiling512.db"), opt.sync, 512, blob, 2.0);
  std::printf(
      "sqlite ceiling (%zu-byte rows, WAL, %s): %.0f rows/s at 1 row/commit, %.0f at 30, "
      "%.0f at 512\n",
      blob, opt.sync.c_str(), one, thirty, big);
  std::printf("ratio: mapd batches/s = %.2fx SQLite 1-row commits/s, %.2f of its 512-row rate\n",
              (stored / seconds) / one, (stored / seconds) / big);
  return rejected == 0 ? 0 : 1;
}
