// What the voxel library's FFT users share (correlation_search.cc,
// yaw_refinement.cc).
#ifndef MAPD_VOXEL_FFT_SUPPORT_H_
#define MAPD_VOXEL_FFT_SUPPORT_H_

#include <algorithm>
#include <mutex>

namespace mapd::voxel {

// FFTW's planner (plan creation and destruction) is not thread-safe; plan
// execution is. Every plan of the library is made and destroyed under this
// one lock, so merges may run concurrently.
inline std::mutex& FftwPlannerMutex() {
  static std::mutex mutex;
  return mutex;
}

// The smallest size >= n with only the factors 2, 3 and 5 (FFTW is fastest
// on those).
inline int FftSize(int n) {
  for (int m = std::max(n, 1);; ++m) {
    int r = m;
    for (int f : {2, 3, 5}) {
      while (r % f == 0) r /= f;
    }
    if (r == 1) return m;
  }
}

}  // namespace mapd::voxel

#endif  // MAPD_VOXEL_FFT_SUPPORT_H_
