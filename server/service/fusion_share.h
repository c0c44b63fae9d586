// Fair use of the fuser (issue 46): one robot must not keep it behind for
// everyone.
//
// The fuser is one thread per map. Acks never wait for it, but the writer
// stops committing new batches once it is max_fusion_backlog observations
// behind (backpressure), and then EVERY robot of the map waits, not only the
// one whose batches cost the time. FusionShare tells that robot apart before
// its batch is queued:
//
//   - per robot, the observations committed but not fused yet (pending), and
//     what the fuser spent on its recent observations (CPU seconds per
//     observation, an exponential average; MapCore measures a random
//     quarter of them);
//   - the work a robot keeps waiting = pending x its cost per observation;
//   - once the work waiting in total exceeds after_s seconds, a batch of a
//     robot whose waiting work exceeds factor times the average of the other
//     robots with work waiting is refused (RESOURCE_EXHAUSTED, the message
//     names the robot, its share and the limit). Nothing is stored, so
//     nothing acknowledged is lost: the robot resends later.
//
// Robots with equal loads are never refused (each is about the average of
// the others), nor is a robot alone on the map (there is no one to starve:
// the backpressure applies as before). A refused robot is admitted again as
// soon as the fuser has worked its backlog down to its share.
//
// Thread safety: every method may be called from any thread.
#ifndef MAPD_SERVICE_FUSION_SHARE_H_
#define MAPD_SERVICE_FUSION_SHARE_H_

#include <chrono>
#include <cstdint>
#include <map>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "common/status.h"

namespace mapd::service {

struct FusionShareOptions {
  // Estimated fuser seconds waiting (all robots) before shares are enforced;
  // 0 disables the check (then only the backpressure protects the map).
  double after_s = 1.0;
  // A robot may keep this many times the others' average waiting. Honest
  // robots differ: in the city soak, where every robot streams at full rate,
  // those in the costlier streets keep 2-3x the average waiting, and with 2
  // they were refused 47,000-67,000 times in 10M features (4: 177); a junk
  // robot keeps hundreds of times the average.
  double factor = 4.0;
  // A refusal is answered after this long (delayed_calls.h): a robot that
  // resends at once is throttled instead of costing mapd a refusal per
  // batch. Seconds; 0 = at once.
  double refusal_delay_s = 0.25;
};

class FusionShare {
 public:
  explicit FusionShare(const FusionShareOptions& options) : options_(options) {}

  // Ok, or ResourceExhausted naming the robot's share when its batch must
  // wait (counted as a refusal).
  Status Admit(const std::string& robot);
  // One observation of `robot` was committed and handed to the fuser.
  void Committed(const std::string& robot);
  // The fuser finished one observation of `robot`, spending cpu_s on it
  // (nullopt: not measured; the cost is an average over those that are).
  void Fused(const std::string& robot, std::optional<double> cpu_s);
  // The fuser stopped (or restarted) with observations pending: forget them.
  void Reset();

  struct RobotShare {
    std::string robot;
    uint64_t pending = 0;         // committed, not fused
    double cost_per_obs_s = 0.0;  // the fuser's CPU per observation, recent average
    uint64_t refused = 0;         // batches refused since the start
  };
  // Robots with observations pending or batches refused, by name.
  std::vector<RobotShare> Shares() const;
  uint64_t refused_total() const;

  // Before the fuser measured a robot: the average over the robots it has
  // measured, else this, seconds per observation.
  static constexpr double kDefaultCostS = 1e-3;
  static constexpr double kCostWeight = 0.05;  // of each new measurement in the average

 private:
  struct Robot {
    uint64_t pending = 0;
    double cost_s = 0.0;  // 0: not measured yet
    uint64_t refused = 0;
    std::chrono::steady_clock::time_point last_logged{};  // of a refusal
  };
  // The cost assumed for a robot not measured yet: the measured robots'
  // average, else kDefaultCostS. REQUIRES: mu_ held.
  double UnmeasuredCost() const;

  const FusionShareOptions options_;
  mutable std::mutex mu_;
  std::map<std::string, Robot> robots_;  // GUARDED_BY(mu_)
  uint64_t refused_total_ = 0;           // GUARDED_BY(mu_)
};

}  // namespace mapd::service

#endif  // MAPD_SERVICE_FUSION_SHARE_H_
