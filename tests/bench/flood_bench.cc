// Stream flood against a real mapd process: client threads open and cancel
// Ingest streams as fast as they can (target --streams in --seconds, the
// HTTP/2 rapid open/cancel pattern) while a health checker and a normal robot
// measure their latency, and mapd's RSS is sampled (peak, and --settle
// seconds after the flood).
//
//   flood_bench [--streams 300000] [--seconds 10] [--threads 4] [--settle 10]
//               [--mapd PATH] [mapd flags after --]
//
// Targets (issue "Safe on a real network"): health p99 < 100 ms, robot ack
// p99 < 100 ms, RSS < 512 MiB, RSS after the flood within 2x of baseline.
// Not a test: run it on demand (see docs/reliability.md).
#include <grpcpp/grpcpp.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <mutex>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include "common/batches.h"
#include "common/health.h"
#include "common/latency_probes.h"
#include "common/process.h"
#include "common/temp_dir.h"
#include "mapserver/v1/map_service.grpc.pb.h"

namespace {

namespace pb = mapserver::v1;
using Clock = std::chrono::steady_clock;
using mapd::testing::Quantile;

// One grpc.health.v1.Health/Check; latency in ms, or -1 on failure.
double HealthCheck(const std::shared_ptr<grpc::Channel>& channel) {
  const auto t0 = Clock::now();
  if (mapd::testing::CheckHealth(channel, std::chrono::seconds(30)) ==
      mapd::testing::Health::kError)
    return -1;
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

}  // namespace

int main(int argc, char** argv) {
  long streams = 300000;
  double seconds = 10, settle = 10;
  int threads = 4;
  std::string mapd_binary = mapd::testing::kDefaultMapdBinary;
  std::vector<std::string> mapd_args;
  for (int i = 1; i < argc; ++i) {
    const std::string k = argv[i];
    if (k == "--") {
      for (++i; i < argc; ++i) mapd_args.push_back(argv[i]);
      break;
    }
    if (i + 1 >= argc) return std::fprintf(stderr, "flood_bench: %s needs a value\n", k.c_str()), 2;
    const std::string v = argv[++i];
    if (k == "--streams")
      streams = std::stol(v);
    else if (k == "--seconds")
      seconds = std::stod(v);
    else if (k == "--threads")
      threads = std::stoi(v);
    else if (k == "--settle")
      settle = std::stod(v);
    else if (k == "--mapd")
      mapd_binary = v;
    else
      return std::fprintf(stderr, "flood_bench: unknown flag %s\n", k.c_str()), 2;
  }
  mapd::testing::TempDir dir;
  const mapd::testing::MapdProcess mapd =
      mapd::testing::StartMapd(dir.File("map.db"), mapd_args, mapd_binary);
  if (mapd.port == 0) {
    std::fprintf(stderr, "flood_bench: mapd did not start:\n%s\n", mapd.log().c_str());
    return 1;
  }
  auto channel = grpc::CreateChannel(mapd.address, grpc::InsecureChannelCredentials());
  auto stub = pb::MapService::NewStub(channel);
  std::this_thread::sleep_for(std::chrono::seconds(1));
  const double rss_baseline = mapd::testing::ResidentMiB(mapd.pid);

  std::atomic<bool> done{false};
  std::atomic<double> rss_peak{rss_baseline};

  // RSS sampler.
  std::thread sampler([&] {
    while (!done) {
      const double r = mapd::testing::ResidentMiB(mapd.pid);
      if (r > rss_peak) rss_peak = r;
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
    }
  });
  // A normal robot and health checks, each on a connection of its own.
  mapd::testing::LatencyProbes probes(mapd.address);

  // The flood: each thread on its own connection(s), paced to the target rate.
  std::this_thread::sleep_for(std::chrono::milliseconds(500));
  std::atomic<long> opened{0}, refused{0};
  const auto t0 = Clock::now();
  std::vector<std::thread> flood;
  for (int t = 0; t < threads; ++t) {
    flood.emplace_back([&, t] {
      grpc::ChannelArguments a;
      a.SetInt("mapd.bench.flood", t);
      auto ch = grpc::CreateCustomChannel(mapd.address, grpc::InsecureChannelCredentials(), a);
      auto s = pb::MapService::NewStub(ch);
      const long mine = streams / threads;
      for (long i = 0; i < mine; ++i) {
        // Pace: stream i of this thread not before its share of the window.
        const auto due =
            t0 + std::chrono::duration<double>(seconds * static_cast<double>(i) / mine);
        if (Clock::now() < due) std::this_thread::sleep_until(due);
        grpc::ClientContext ctx;
        ctx.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(10));
        auto stream = s->Ingest(&ctx);
        ctx.TryCancel();
        const grpc::Status st = stream->Finish();
        ++opened;
        if (st.error_code() == grpc::StatusCode::RESOURCE_EXHAUSTED) ++refused;
      }
    });
  }
  for (auto& t : flood) t.join();
  const double flood_s = std::chrono::duration<double>(Clock::now() - t0).count();
  const mapd::testing::LatencyProbes::Result probed = probes.Stop();
  const double rss_flood_peak = rss_peak;
  std::this_thread::sleep_for(std::chrono::duration<double>(settle));
  const double rss_after = mapd::testing::ResidentMiB(mapd.pid);
  done = true;
  sampler.join();
  const double health_after = HealthCheck(channel);
  mapd::testing::Stop(mapd.pid, SIGTERM);

  long log_lines = 0;
  {
    std::ifstream log(mapd.log_path);
    std::string line;
    while (std::getline(log, line)) ++log_lines;
  }
  std::printf(
      "flood: %ld streams opened+cancelled in %.2f s (%.0f/s) from %d threads; %ld refused "
      "RESOURCE_EXHAUSTED by the server\n",
      opened.load(), flood_s, opened.load() / flood_s, threads, refused.load());
  std::printf(
      "health: %zu checks, p50 %.1f ms, p99 %.1f ms, max %.1f ms, %ld failed; after the flood %.1f "
      "ms\n",
      probed.health_ms.size(), Quantile(probed.health_ms, 0.5), Quantile(probed.health_ms, 0.99),
      Quantile(probed.health_ms, 1.0), probed.health_failures, health_after);
  std::printf(
      "robot: %zu acks (%ld stored, %ld other), ack p50 %.1f ms, p99 %.1f ms, max %.1f ms\n",
      probed.ack_ms.size(), probed.acks_stored, probed.acks_other, Quantile(probed.ack_ms, 0.5),
      Quantile(probed.ack_ms, 0.99), Quantile(probed.ack_ms, 1.0));
  std::printf(
      "mapd RSS: baseline %.0f MiB, peak %.0f MiB, %.0f s after the flood %.0f MiB (%.2fx "
      "baseline)\n",
      rss_baseline, rss_flood_peak, settle, rss_after, rss_after / rss_baseline);
  std::printf("mapd log: %ld lines\n", log_lines);
  return 0;
}
