#include "voxel/large_array.h"

#include <sys/mman.h>

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstdlib>

namespace mapd::voxel::internal {
namespace {

std::size_t RoundUp(std::size_t bytes, std::size_t to) { return (bytes + to - 1) / to * to; }

}  // namespace

void* AllocateLarge(std::size_t bytes) {
  // No block can be this large, and rounding it up would wrap around.
  if (bytes > static_cast<std::size_t>(PTRDIFF_MAX)) throw std::bad_alloc();
  if (bytes < kHugePageBytes) {
    // Small blocks: the heap (aligned for FFTW's SIMD loads).
    void* p = std::aligned_alloc(64, RoundUp(std::max<std::size_t>(bytes, 1), 64));
    if (p == nullptr) throw std::bad_alloc();
    return p;
  }
  const std::size_t size = RoundUp(bytes, kHugePageBytes);
  // Over-map by one huge page and trim both ends, so the block starts on a
  // huge page boundary (mmap promises only 4 KiB alignment).
  void* mapped = mmap(nullptr, size + kHugePageBytes, PROT_READ | PROT_WRITE,
                      MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
  if (mapped == MAP_FAILED) throw std::bad_alloc();
  const auto begin = reinterpret_cast<std::uintptr_t>(mapped);
  const std::uintptr_t aligned = RoundUp(begin, kHugePageBytes);
  if (aligned > begin) munmap(mapped, aligned - begin);
  const std::size_t tail = begin + kHugePageBytes - aligned;
  if (tail > 0) munmap(reinterpret_cast<void*>(aligned + size), tail);
  // Advice only: where THP is off the block works with small pages.
  madvise(reinterpret_cast<void*>(aligned), size, MADV_HUGEPAGE);
  return reinterpret_cast<void*>(aligned);
}

void FreeLarge(void* p, std::size_t bytes) {
  if (p == nullptr) return;
  if (bytes < kHugePageBytes) {
    std::free(p);
    return;
  }
  munmap(p, RoundUp(bytes, kHugePageBytes));
}

}  // namespace mapd::voxel::internal
