// One robot's junk beside a working fleet, through a real mapd (issue 46):
// 4 robots loop a 10 x 8 m room at a fixed rate while one robot streams, as
// fast as acks allow, the room plus 4 random axis-aligned 2 m walls anywhere
// in a 100 x 100 m area (valid input: a broken feature extractor). Reports
// the 4 robots' acknowledgement latency, what the junk robot was told, how
// far the fuser fell behind, whether the 4 robots' map is the one they get
// without the junk robot, and how long SIGTERM takes to end mapd with the
// junk still streaming, and whether every batch acknowledged as stored is in
// the database after the stop. A benchmark, not a test: figures go to
// docs/reliability.md.
//
//   junk_bench [--seconds 40] [--rate-hz 20] [--junk 1] [--mapd PATH] [--mapd-arg ARG]...
//
// The junk lies 200 m east of the room, so "the same map" has a meaning:
// the room's published walls with and without the junk robot (--junk 0).
// JUNK_BENCH_LOG=1 prints each mapd's log after its stop.
#include <grpcpp/grpcpp.h>
#include <signal.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <map>
#include <mutex>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include "common/batches.h"
#include "common/clock.h"
#include "common/process.h"
#include "common/temp_dir.h"
#include "mapserver/v1/map_service.grpc.pb.h"

namespace {

namespace pb = mapserver::v1;
using Clock = std::chrono::steady_clock;

struct Options {
  double seconds = 40;
  double rate_hz = 20;  // per floor robot
  int junk = 1;
  std::string mapd = MAPD_BINARY;
  std::vector<std::string> mapd_args;  // --mapd-arg, repeated
};

struct StreamResult {
  std::vector<double> latencies_ms;
  uint64_t stored = 0, rejected = 0, exhausted = 0;
  std::string first_refusal;
  std::string final_status = "(none)";
  double final_after_stop_s = -1;  // from the end of sending to the stream's final status
};

// The junk batch: the room moved 200 m east, plus 4 random walls, map frame.
pb::ObservationBatch JunkBatch(std::mt19937_64& rng, uint64_t seq) {
  pb::ObservationBatch b;
  b.set_robot_id("junk");
  b.set_session_id("s");
  b.set_seq(seq);
  b.set_stamp_ns(static_cast<int64_t>(seq) * 1000000);
  auto* pose = b.mutable_t_frame_sensor();
  pose->mutable_translation()->set_x(205);
  pose->mutable_translation()->set_y(4);
  pose->mutable_rotation()->set_w(1);
  std::normal_distribution<double> noise(0.0, 0.02);
  std::uniform_real_distribution<double> pos(-45.0, 55.0);
  const auto add = [&](double ax, double ay, double bx, double by) {
    auto* line = b.add_lines();  // sensor frame = map frame shifted by the pose
    line->mutable_a()->set_x(ax - 205);
    line->mutable_a()->set_y(ay - 4);
    line->mutable_b()->set_x(bx - 205);
    line->mutable_b()->set_y(by - 4);
  };
  for (const mapd::testing::Wall& w : mapd::testing::RoomWalls()) {
    const Eigen::Vector2d d = w.b - w.a;
    const Eigen::Vector2d a = w.a + 0.1 * d, c = w.a + 0.9 * d;
    add(200 + a.x() + noise(rng), a.y() + noise(rng), 200 + c.x() + noise(rng), c.y() + noise(rng));
  }
  for (int i = 0; i < 4; ++i) {
    const double x = 200 + pos(rng), y = pos(rng);
    if (rng() % 2) {
      add(x, y, x + 2, y);
    } else {
      add(x, y, x, y + 2);
    }
  }
  return b;
}

// Streams batches from `make` until `stop`, at most `window` unacknowledged,
// one every 1 / rate_hz seconds (0: as fast as acks allow).
void Stream(const std::shared_ptr<grpc::Channel>& channel, double rate_hz, int window,
            const std::function<pb::ObservationBatch(uint64_t)>& make,
            const std::atomic<bool>& stop, StreamResult* result) {
  auto stub = pb::MapService::NewStub(channel);
  grpc::ClientContext ctx;
  auto stream = stub->Ingest(&ctx);
  std::mutex mu;
  std::condition_variable cv;
  int in_flight = 0;
  std::map<uint64_t, int64_t> sent_ns;
  std::thread reader([&] {
    pb::IngestAck ack;
    while (stream->Read(&ack)) {
      const int64_t now = mapd::SteadyNowNs();
      std::lock_guard<std::mutex> lock(mu);
      result->latencies_ms.push_back(static_cast<double>(now - sent_ns[ack.seq()]) / 1e6);
      sent_ns.erase(ack.seq());
      if (ack.result() == pb::IngestAck::STORED || ack.result() == pb::IngestAck::DUPLICATE) {
        ++result->stored;
      } else {
        ++result->rejected;
        if (ack.code() == grpc::StatusCode::RESOURCE_EXHAUSTED) ++result->exhausted;
        if (result->first_refusal.empty()) result->first_refusal = ack.message();
      }
      --in_flight;
      cv.notify_one();
    }
  });
  const auto start = Clock::now();
  for (uint64_t seq = 1; !stop.load(); ++seq) {
    if (rate_hz > 0) {
      std::this_thread::sleep_until(
          start + std::chrono::duration_cast<Clock::duration>(
                      std::chrono::duration<double>(static_cast<double>(seq - 1) / rate_hz)));
    }
    {
      std::unique_lock<std::mutex> lock(mu);
      // Polls `stop` too: nobody notifies when it is set.
      while (in_flight >= window && !stop.load()) cv.wait_for(lock, std::chrono::milliseconds(50));
      if (stop.load()) break;
      ++in_flight;
      sent_ns[seq] = mapd::SteadyNowNs();
    }
    if (!stream->Write(make(seq))) break;
  }
  const auto stopped = Clock::now();
  stream->WritesDone();
  reader.join();
  const grpc::Status s = stream->Finish();
  result->final_after_stop_s = std::chrono::duration<double>(Clock::now() - stopped).count();
  result->final_status = s.ok() ? "OK" : std::to_string(s.error_code()) + " " + s.error_message();
}

double Percentile(std::vector<double> v, double p) {
  if (v.empty()) return 0;
  const size_t k = std::min(v.size() - 1, static_cast<size_t>(p * static_cast<double>(v.size())));
  std::nth_element(v.begin(), v.begin() + static_cast<long>(k), v.end());
  return v[k];
}

// The room's published walls (bbox around the room).
std::vector<pb::FusedFeature> RoomMap(pb::MapService::Stub* stub) {
  pb::FeatureMapRequest request;
  request.mutable_bbox()->mutable_min()->set_x(-5);
  request.mutable_bbox()->mutable_min()->set_y(-5);
  request.mutable_bbox()->mutable_max()->set_x(15);
  request.mutable_bbox()->mutable_max()->set_y(13);
  request.set_max_wait_ms(120000);
  grpc::ClientContext ctx;
  auto reader = stub->GetFeatureMap(&ctx, request);
  std::vector<pb::FusedFeature> out;
  pb::FeatureMapPage page;
  while (reader->Read(&page)) out.insert(out.end(), page.features().begin(), page.features().end());
  reader->Finish();
  return out;
}

struct RunResult {
  std::vector<double> floor_ms;
  uint64_t floor_stored = 0, floor_rejected = 0;
  StreamResult junk;
  uint64_t max_backlog = 0, junk_refused_stats = 0;
  std::vector<pb::FusedFeature> room;
  double stop_s = 0;
  int exit_status = 0;
  std::string floor_final;
  double floor_final_s = 0;
  // After the stop, from a restarted mapd: batches stored per robot.
  std::map<std::string, uint64_t> stored_after;
  std::map<std::string, uint64_t> acked;  // acknowledged STORED or DUPLICATE
};

// Batches stored per robot, from a mapd started on the database `db`.
std::map<std::string, uint64_t> StoredBatches(const std::string& db, const Options& opt) {
  std::map<std::string, uint64_t> out;
  const mapd::testing::MapdProcess mapd = mapd::testing::StartMapd(db, opt.mapd_args, opt.mapd);
  if (mapd.port == 0) return out;
  auto stub = pb::MapService::NewStub(
      grpc::CreateChannel(mapd.address, grpc::InsecureChannelCredentials()));
  for (int attempt = 0; attempt < 1200 && out.empty(); ++attempt) {
    grpc::ClientContext ctx;
    pb::ListRobotsResponse robots;
    if (stub->ListRobots(&ctx, {}, &robots).ok()) {
      for (const pb::RobotInfo& r : robots.robots()) out[r.robot_id()] = r.batches();
    } else {
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
    }
  }
  mapd::testing::Stop(mapd.pid, SIGTERM, std::chrono::seconds(120));
  return out;
}

RunResult Run(const Options& opt, bool with_junk) {
  mapd::testing::TempDir dir;
  const mapd::testing::MapdProcess mapd =
      mapd::testing::StartMapd(dir.File("map.db"), opt.mapd_args, opt.mapd);
  RunResult r;
  if (mapd.port == 0) {
    std::fprintf(stderr, "junk_bench: mapd did not start:\n%s\n", mapd.log().c_str());
    std::exit(1);
  }
  std::atomic<bool> stop_floor{false}, stop_junk{false};
  std::vector<StreamResult> floor(4);
  std::vector<std::thread> threads;
  for (int i = 0; i < 4; ++i) {
    auto channel = grpc::CreateChannel(mapd.address, grpc::InsecureChannelCredentials());
    threads.emplace_back([&, i, channel] {
      std::mt19937_64 rng(100 + static_cast<uint64_t>(i));
      std::uniform_real_distribution<double> x(2, 8), y(2, 6), yaw(-M_PI, M_PI);
      const std::string robot = "floor-" + std::to_string(i);
      Stream(
          channel, opt.rate_hz, 64,
          [&](uint64_t seq) {
            return mapd::testing::RoomBatch(robot, "s", seq, x(rng), y(rng), yaw(rng), &rng);
          },
          stop_floor, &floor[static_cast<size_t>(i)]);
    });
  }
  std::thread junk;
  if (with_junk) {
    auto channel = grpc::CreateChannel(mapd.address, grpc::InsecureChannelCredentials());
    junk = std::thread([&, channel] {
      std::mt19937_64 rng(46);
      Stream(
          channel, 0, 256, [&](uint64_t seq) { return JunkBatch(rng, seq); }, stop_junk, &r.junk);
    });
  }
  auto stats_channel = grpc::CreateChannel(mapd.address, grpc::InsecureChannelCredentials());
  auto stub = pb::MapService::NewStub(stats_channel);
  const auto t0 = Clock::now();
  while (Clock::now() - t0 < std::chrono::duration<double>(opt.seconds)) {
    std::this_thread::sleep_for(std::chrono::milliseconds(250));
    grpc::ClientContext ctx;
    pb::Stats stats;
    if (stub->GetStats(&ctx, {}, &stats).ok()) {
      r.max_backlog = std::max<uint64_t>(r.max_backlog, stats.fusion_backlog());
      r.junk_refused_stats = stats.fusion_share_refused();
    }
  }
  stop_floor = true;
  for (auto& t : threads) t.join();
  for (const StreamResult& f : floor) {
    r.floor_ms.insert(r.floor_ms.end(), f.latencies_ms.begin(), f.latencies_ms.end());
    r.floor_stored += f.stored;
    r.floor_rejected += f.rejected;
    r.floor_final = f.final_status;
    r.floor_final_s = std::max(r.floor_final_s, f.final_after_stop_s);
  }
  // The floor robots' map, once the fuser reflects every batch they sent
  // (the junk robot goes on streaming).
  r.room = RoomMap(stub.get());
  // SIGTERM with the junk robot still streaming and the fuser behind.
  const auto term = Clock::now();
  r.exit_status = mapd::testing::Stop(mapd.pid, SIGTERM, std::chrono::seconds(120));
  r.stop_s = std::chrono::duration<double>(Clock::now() - term).count();
  if (std::getenv("JUNK_BENCH_LOG")) std::fprintf(stderr, "%s\n", mapd.log().c_str());
  stop_junk = true;
  if (junk.joinable()) junk.join();
  // Nothing acknowledged is lost: every batch acknowledged as stored is in
  // the database a new mapd opens.
  for (int i = 0; i < 4; ++i)
    r.acked["floor-" + std::to_string(i)] = floor[static_cast<size_t>(i)].stored;
  if (with_junk) r.acked["junk"] = r.junk.stored;
  r.stored_after = StoredBatches(dir.File("map.db"), opt);
  return r;
}

double SegmentGap(const pb::FusedFeature& f, const pb::FusedFeature& g) {
  const auto d = [](const pb::Vec2& p, const pb::Vec2& q) {
    return std::hypot(p.x() - q.x(), p.y() - q.y());
  };
  return std::min(std::max(d(f.a(), g.a()), d(f.b(), g.b())),
                  std::max(d(f.a(), g.b()), d(f.b(), g.a())));
}

}  // namespace

int main(int argc, char** argv) {
  Options opt;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string k = argv[i], v = argv[i + 1];
    if (k == "--seconds") {
      opt.seconds = std::stod(v);
    } else if (k == "--rate-hz") {
      opt.rate_hz = std::stod(v);
    } else if (k == "--junk") {
      opt.junk = std::stoi(v);
    } else if (k == "--mapd") {
      opt.mapd = v;
    } else if (k == "--mapd-arg") {
      opt.mapd_args.push_back(v);
    } else {
      std::fprintf(stderr,
                   "usage: junk_bench [--seconds S] [--rate-hz R] [--junk 0|1] [--mapd PATH] "
                   "[--mapd-arg ARG]...\n");
      return 2;
    }
  }
  const RunResult base = Run(opt, false);
  const RunResult r = opt.junk ? Run(opt, true) : base;
  std::printf("4 floor robots at %.0f Hz each for %.0f s%s\n", opt.rate_hz, opt.seconds,
              opt.junk ? ", 1 junk robot as fast as acks allow" : "");
  for (const RunResult* run : {&base, &r}) {
    std::printf(
        "%s: floor acks p50 %.1f ms, p99 %.1f ms, max %.1f ms; %llu stored, %llu refused; "
        "max fusion backlog %llu; floor streams ended %s within %.2f s\n",
        run == &base ? "without junk" : "with junk   ", Percentile(run->floor_ms, 0.5),
        Percentile(run->floor_ms, 0.99), Percentile(run->floor_ms, 1.0),
        static_cast<unsigned long long>(run->floor_stored),
        static_cast<unsigned long long>(run->floor_rejected),
        static_cast<unsigned long long>(run->max_backlog), run->floor_final.c_str(),
        run->floor_final_s);
    std::printf("  SIGTERM to exit: %.2f s (status %d)\n", run->stop_s, run->exit_status);
    std::string lost;
    for (const auto& [robot, acked] : run->acked) {
      const auto it = run->stored_after.find(robot);
      const uint64_t stored = it == run->stored_after.end() ? 0 : it->second;
      std::printf("  %s: %llu acknowledged as stored, %llu in the database after a restart\n",
                  robot.c_str(), static_cast<unsigned long long>(acked),
                  static_cast<unsigned long long>(stored));
      if (stored < acked) lost += " " + robot;
    }
    std::printf("  acknowledged and lost: %s\n", lost.empty() ? "none" : lost.c_str());
    if (run == &base && !opt.junk) break;
  }
  if (opt.junk) {
    std::printf(
        "junk robot: %llu stored, %llu refused (%llu RESOURCE_EXHAUSTED; GetStats says %llu); "
        "acks p50 %.1f ms, p99 %.1f ms; its stream ended %s\n",
        static_cast<unsigned long long>(r.junk.stored),
        static_cast<unsigned long long>(r.junk.rejected),
        static_cast<unsigned long long>(r.junk.exhausted),
        static_cast<unsigned long long>(r.junk_refused_stats), Percentile(r.junk.latencies_ms, 0.5),
        Percentile(r.junk.latencies_ms, 0.99), r.junk.final_status.c_str());
    std::printf("  first refusal: %s\n", r.junk.first_refusal.c_str());
    double worst = 0;
    for (const pb::FusedFeature& f : r.room) {
      double best = HUGE_VAL;
      for (const pb::FusedFeature& g : base.room) best = std::min(best, SegmentGap(f, g));
      worst = std::max(worst, best);
    }
    std::printf("room map: %zu walls without junk, %zu with; farthest wall from its match %.3f m\n",
                base.room.size(), r.room.size(), worst);
  }
  return 0;
}
