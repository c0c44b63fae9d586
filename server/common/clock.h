// Wall-clock time for records (received_ns, created_ns, logs): nanoseconds
// since the Unix epoch. Durations use std::chrono::steady_clock instead.
#ifndef MAPD_COMMON_CLOCK_H_
#define MAPD_COMMON_CLOCK_H_

#include <chrono>
#include <cstdint>

namespace mapd {

inline int64_t UnixNowNs() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

}  // namespace mapd

#endif  // MAPD_COMMON_CLOCK_H_
