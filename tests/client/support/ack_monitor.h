// Watches a fleet of StreamingRobot for the failover test and benchmark:
// what a robot of each map sees of a takeover or handoff is the longest
// pause between two of its acknowledgements.
#ifndef MAPD_TESTS_CLIENT_SUPPORT_ACK_MONITOR_H_
#define MAPD_TESTS_CLIENT_SUPPORT_ACK_MONITOR_H_

#include <algorithm>
#include <atomic>
#include <chrono>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "client/support/streaming_robot.h"

namespace mapd::testing {

// Samples every robot's acknowledgements every 5 ms: the time of each map's
// last ack, and the longest pause between acks since Reset().
class AckMonitor {
 public:
  explicit AckMonitor(const std::vector<std::unique_ptr<StreamingRobot>>* robots)
      : robots_(robots), thread_([this] { Loop(); }) {}
  ~AckMonitor() {
    stop_ = true;
    thread_.join();
  }
  void Reset() {
    std::lock_guard<std::mutex> lock(mu_);
    longest_.clear();
  }
  std::map<std::string, double> Longest() const {
    std::lock_guard<std::mutex> lock(mu_);
    return longest_;
  }

 private:
  void Loop() {
    std::map<std::string, uint64_t> acked;
    std::map<std::string, std::chrono::steady_clock::time_point> last;
    while (!stop_) {
      const auto now = std::chrono::steady_clock::now();
      {
        std::lock_guard<std::mutex> lock(mu_);
        for (const auto& r : *robots_) {
          const uint64_t a = r->acked();
          if (last.count(r->map()) == 0) last[r->map()] = now;
          if (a != acked[r->map()]) {
            acked[r->map()] = a;
            last[r->map()] = now;
          }
          double& longest = longest_[r->map()];
          longest = std::max(longest, std::chrono::duration<double>(now - last[r->map()]).count());
        }
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
  }

  const std::vector<std::unique_ptr<StreamingRobot>>* robots_;
  mutable std::mutex mu_;
  std::map<std::string, double> longest_;
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

}  // namespace mapd::testing

#endif  // MAPD_TESTS_CLIENT_SUPPORT_ACK_MONITOR_H_
