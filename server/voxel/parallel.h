// ParallelFor: the merge's independent pieces of work (the inputs' views, the
// plan view's yaw candidates) on the threads a merge is given
// (MergeParams::threads). Results go to per-index slots, so they do not
// depend on the thread count or on scheduling.
//
// Thread safety: fn is called concurrently for different indices; it must
// only share what is safe to share.
#ifndef MAPD_VOXEL_PARALLEL_H_
#define MAPD_VOXEL_PARALLEL_H_

#include <algorithm>
#include <atomic>
#include <cstddef>
#include <iterator>
#include <system_error>
#include <thread>
#include <vector>

namespace mapd::voxel {

// Calls fn(i, worker) for every i in [0, n), on min(threads, n) threads (the
// caller's is one of them), worker in [0, that): indices are taken in
// ascending order as workers free up. threads <= 1: in order on the caller's
// thread, worker 0. Returns when every call has returned. fn must not throw.
template <typename Fn>
void ParallelFor(std::size_t n, int threads, const Fn& fn) {
  const std::size_t workers = std::min<std::size_t>(n, threads > 1 ? threads : 1);
  if (workers <= 1) {
    for (std::size_t i = 0; i < n; ++i) fn(i, std::size_t{0});
    return;
  }
  std::atomic<std::size_t> next{0};
  const auto work = [&](std::size_t worker) {
    for (std::size_t i = next++; i < n; i = next++) fn(i, worker);
  };
  std::vector<std::thread> helpers;
  helpers.reserve(workers - 1);
  for (std::size_t w = 1; w < workers; ++w) {
    // A process at its thread limit gets fewer helpers, not an exception
    // (mapd would end): the indices are shared, so fewer workers do them all.
    try {
      helpers.emplace_back(work, w);
    } catch (const std::system_error&) {
      break;
    }
  }
  work(0);
  for (std::thread& t : helpers) t.join();
}

// Calls fn(begin, end) on `threads` contiguous parts of [0, n) at once (one
// part per thread; fewer for small n): element-wise loops over large grids.
template <typename Fn>
void ParallelRanges(std::size_t n, int threads, const Fn& fn) {
  constexpr std::size_t kMinPart = 1 << 16;  // smaller parts cost more to start than they save
  const std::size_t parts =
      std::max<std::size_t>(1, std::min<std::size_t>(threads > 1 ? threads : 1, n / kMinPart));
  ParallelFor(parts, static_cast<int>(parts),
              [&](std::size_t part, std::size_t) { fn(n * part / parts, n * (part + 1) / parts); });
}

// std::sort of [first, last) on up to `threads` threads: contiguous parts
// sorted at once, then merged pairwise. The same order as std::sort for
// values that compare equal only when identical (keys, codes).
template <typename It>
void ParallelSort(It first, It last, int threads) {
  const auto n = static_cast<std::size_t>(last - first);
  constexpr std::size_t kMinPart = 1 << 16;
  std::size_t parts = 1;
  while (parts * 2 <= static_cast<std::size_t>(threads > 1 ? threads : 1) &&
         n / (parts * 2) >= kMinPart) {
    parts *= 2;
  }
  const auto at = [&](std::size_t part) {
    return first + static_cast<std::ptrdiff_t>(n * part / parts);
  };
  ParallelFor(parts, static_cast<int>(parts),
              [&](std::size_t part, std::size_t) { std::sort(at(part), at(part + 1)); });
  for (std::size_t width = 1; width < parts; width *= 2) {
    ParallelFor(parts / (2 * width), static_cast<int>(parts / (2 * width)),
                [&](std::size_t k, std::size_t) {
                  const std::size_t lo = 2 * width * k;
                  std::inplace_merge(at(lo), at(lo + width), at(lo + 2 * width));
                });
  }
}

}  // namespace mapd::voxel

#endif  // MAPD_VOXEL_PARALLEL_H_
