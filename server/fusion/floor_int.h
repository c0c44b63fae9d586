// Floor and ceiling to an integer, inline. std::floor and std::ceil are
// calls into libm on the x86-64 baseline (SSE4.1's roundsd is not assumed),
// and the fuser takes them for every cell it visits: grid keys, free-space
// rows and samples (3-4 % of its CPU in the city workload).
#ifndef MAPD_FUSION_FLOOR_INT_H_
#define MAPD_FUSION_FLOOR_INT_H_

#include <cstdint>

namespace mapd::fusion {

// REQUIRES: x finite and |x| < 2^62 (cell indices of coordinates the
// engine's input check bounds by 1e6 m). Equal to std::floor / std::ceil.
inline int64_t FloorInt(double x) {
  const auto t = static_cast<int64_t>(x);  // rounds toward zero
  return t - static_cast<int64_t>(static_cast<double>(t) > x);
}
inline int64_t CeilInt(double x) {
  const auto t = static_cast<int64_t>(x);
  return t + static_cast<int64_t>(static_cast<double>(t) < x);
}

}  // namespace mapd::fusion

#endif  // MAPD_FUSION_FLOOR_INT_H_
