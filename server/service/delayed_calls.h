// Calls run later, on a thread of their own (MapCore's refusals of a robot
// over its fusion share: fusion_share.h).
//
// A refused batch is answered at once, and a robot (or a broken client) that
// resends at once makes mapd refuse thousands of batches a second, taking the
// CPU the other robots' streams need. Answering a refusal after a delay
// throttles such a robot instead: its stream's unacknowledged batches
// (limits.max_in_flight) stay in flight, so mapd stops reading from it.
//
// Thread safety: every method may be called from any thread.
#ifndef MAPD_SERVICE_DELAYED_CALLS_H_
#define MAPD_SERVICE_DELAYED_CALLS_H_

#include <chrono>
#include <condition_variable>
#include <functional>
#include <map>
#include <mutex>
#include <thread>

namespace mapd::service {

class DelayedCalls {
 public:
  DelayedCalls();
  ~DelayedCalls();  // Stop()

  // Runs `fn` once `delay` has passed (at once after Stop()).
  void Post(std::chrono::steady_clock::duration delay, std::function<void()> fn);
  // Runs every call still waiting, now, and ends the thread. Idempotent.
  void Stop();

 private:
  void Loop();

  std::mutex mu_;
  std::condition_variable cv_;
  // By deadline; equal deadlines in the order posted.
  std::multimap<std::chrono::steady_clock::time_point, std::function<void()>>
      calls_;              // GUARDED_BY(mu_)
  bool stopping_ = false;  // GUARDED_BY(mu_)
  std::thread thread_;
};

}  // namespace mapd::service

#endif  // MAPD_SERVICE_DELAYED_CALLS_H_
