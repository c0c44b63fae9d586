// What a flood costs the clients that matter: a normal robot streaming a batch
// every 10 ms on its own connection (the latency of each acknowledgement) and
// a health checker asking every 20 ms on another. Both run from construction
// to Stop(). Header-only; for the flood benchmarks and tests.
//
//   LatencyProbes probes(mapd.address);
//   ... flood ...
//   const LatencyProbes::Result r = probes.Stop();
#ifndef MAPD_TESTS_COMMON_LATENCY_PROBES_H_
#define MAPD_TESTS_COMMON_LATENCY_PROBES_H_

#include <grpcpp/grpcpp.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <mutex>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include "common/batches.h"
#include "common/health.h"
#include "mapserver/v1/map_service.grpc.pb.h"

namespace mapd::testing {

// The q-quantile (0..1, 1 = max) of `v`; 0 if empty.
inline double Quantile(std::vector<double> v, double q) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  return v[std::min(v.size() - 1, static_cast<size_t>(q * static_cast<double>(v.size())))];
}

class LatencyProbes {
 public:
  struct Result {
    std::vector<double> ack_ms;  // per acknowledged batch, send to ack
    long batches_sent = 0;
    long acks_stored = 0, acks_other = 0;
    std::vector<double> health_ms;  // per answered check
    long health_failures = 0;
  };

  explicit LatencyProbes(const std::string& address) {
    health_ = std::thread([this, address] { CheckHealth(address); });
    robot_ = std::thread([this, address] { StreamRobot(address); });
  }
  ~LatencyProbes() { Stop(); }
  LatencyProbes(const LatencyProbes&) = delete;
  LatencyProbes& operator=(const LatencyProbes&) = delete;

  // Ends the robot's stream (waiting for its last acknowledgements) and the
  // health checks.
  Result Stop() {
    running_ = false;
    if (health_.joinable()) health_.join();
    if (robot_.joinable()) robot_.join();
    std::lock_guard<std::mutex> lock(mu_);
    return result_;
  }

 private:
  using Clock = std::chrono::steady_clock;

  // Each probe on a connection of its own (distinct channel arguments).
  static std::shared_ptr<grpc::Channel> Channel(const std::string& address, const char* tag) {
    grpc::ChannelArguments args;
    args.SetInt(tag, 1);
    return grpc::CreateCustomChannel(address, grpc::InsecureChannelCredentials(), args);
  }

  void CheckHealth(const std::string& address) {
    const auto channel = Channel(address, "mapd.probe.health");
    while (running_) {
      const auto t0 = Clock::now();
      const bool ok =
          testing::CheckHealth(channel, std::chrono::seconds(30)) != testing::Health::kError;
      const double ms = std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
      {
        std::lock_guard<std::mutex> lock(mu_);
        if (ok)
          result_.health_ms.push_back(ms);
        else
          ++result_.health_failures;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
  }

  void StreamRobot(const std::string& address) {
    auto stub = mapserver::v1::MapService::NewStub(Channel(address, "mapd.probe.robot"));
    grpc::ClientContext ctx;
    auto stream = stub->Ingest(&ctx);
    std::vector<Clock::time_point> sent;  // by seq - 1; guarded by mu_
    std::thread reader([&] {
      mapserver::v1::IngestAck ack;
      while (stream->Read(&ack)) {
        const auto now = Clock::now();
        std::lock_guard<std::mutex> lock(mu_);
        if (ack.seq() >= 1 && ack.seq() <= sent.size())
          result_.ack_ms.push_back(
              std::chrono::duration<double, std::milli>(now - sent[ack.seq() - 1]).count());
        (ack.result() == mapserver::v1::IngestAck::STORED ? result_.acks_stored
                                                          : result_.acks_other)++;
      }
    });
    std::mt19937_64 rng(7);
    for (uint64_t seq = 1; running_; ++seq) {
      const auto batch = RoomBatch("probe-robot", "s1", seq, 2.0 + 0.01 * seq, 4.0, 0.0, &rng);
      {
        std::lock_guard<std::mutex> lock(mu_);
        sent.push_back(Clock::now());
        ++result_.batches_sent;
      }
      if (!stream->Write(batch)) break;
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    stream->WritesDone();
    reader.join();
    stream->Finish();
  }

  std::atomic<bool> running_{true};
  std::mutex mu_;
  Result result_;
  std::thread health_, robot_;
};

}  // namespace mapd::testing

#endif  // MAPD_TESTS_COMMON_LATENCY_PROBES_H_
