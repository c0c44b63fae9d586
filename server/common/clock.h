// The project's clocks, so that every binary reads time the same way.
#ifndef MAPD_COMMON_CLOCK_H_
#define MAPD_COMMON_CLOCK_H_

#include <time.h>

#include <chrono>
#include <cstdint>

namespace mapd {

// Wall-clock time for records (received_ns, created_ns, logs, batch stamps):
// nanoseconds since the Unix epoch. Jumps when the system clock is set.
inline int64_t UnixNowNs() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

// Monotonic time for durations and latencies: nanoseconds since an unspecified
// start (std::chrono::steady_clock); only differences mean anything.
inline int64_t SteadyNowNs() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(
             std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

// Seconds of std::chrono::steady_clock since `start` (stage times, budgets).
inline double SecondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

// CPU time of the calling thread, seconds: what the thread itself spent,
// whatever else the machine ran meanwhile (costs, not latencies).
inline double ThreadCpuSeconds() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

}  // namespace mapd

#endif  // MAPD_COMMON_CLOCK_H_
