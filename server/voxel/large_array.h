// Storage for the merge's large arrays (correlation grids and spectra, the
// yaw refinement's images, FFT buffers): blocks of 2 MiB and more are mapped
// on their own, aligned to 2 MiB and marked for transparent huge pages.
//
// Why: a merge of two 150k-voxel campus submaps touches ~0.9 GB of fresh
// memory (16M-cell grids per yaw, their spectra). With 4 KiB pages that is
// ~240k page faults, and on a virtual machine a fault costs microseconds:
// 19 % of such a merge was the kernel's. Debian's default THP mode is
// "madvise", so huge pages are used only where asked for; these blocks ask.
// Blocks are unmapped when freed, so a long-running server returns a merge's
// peak to the system (glibc keeps heap memory below its mmap threshold).
#ifndef MAPD_VOXEL_LARGE_ARRAY_H_
#define MAPD_VOXEL_LARGE_ARRAY_H_

#include <cstddef>
#include <cstring>
#include <new>
#include <type_traits>
#include <utility>
#include <vector>

#include "voxel/parallel.h"

namespace mapd::voxel {

namespace internal {
// `bytes` of memory, aligned to 64 bytes at least; huge-page aligned
// and advised when `bytes` >= kHugePageBytes. Throws std::bad_alloc when the
// system has no memory left (as operator new).
void* AllocateLarge(std::size_t bytes);
void FreeLarge(void* p, std::size_t bytes);
inline constexpr std::size_t kHugePageBytes = std::size_t{2} << 20;
}  // namespace internal

// A std::allocator for large, short-lived arrays (see the file comment).
template <typename T>
struct LargeArrayAllocator {
  using value_type = T;
  LargeArrayAllocator() = default;
  template <typename U>
  LargeArrayAllocator(const LargeArrayAllocator<U>& /*other*/) {}  // NOLINT: rebinding
  T* allocate(std::size_t n) {
    if (n > static_cast<std::size_t>(-1) / sizeof(T)) throw std::bad_array_new_length();
    return static_cast<T*>(internal::AllocateLarge(n * sizeof(T)));
  }
  void deallocate(T* p, std::size_t n) { internal::FreeLarge(p, n * sizeof(T)); }
  template <typename U>
  bool operator==(const LargeArrayAllocator<U>& /*other*/) const {
    return true;
  }
  template <typename U>
  bool operator!=(const LargeArrayAllocator<U>& /*other*/) const {
    return false;
  }
};

template <typename T>
using LargeVector = std::vector<T, LargeArrayAllocator<T>>;

// A fixed number of zeros of a trivial type in AllocateLarge's memory, for
// padded grids of which a merge touches a part. A block of a huge page or
// more is a fresh mapping, which the kernel zeroes page by page on first
// touch, so the pages never touched cost nothing; LargeVector's assign(n, 0)
// writes, and so faults in, every page. (A campus crop's 11.5M-cell
// correlation grid holds its content in a fifth of it: docs/archive/voxel-merge-history.md,
// "Leaf walks by recursion; untouched zeros".) Smaller blocks are zeroed
// here. Move-only.
template <typename T>
class ZeroedLargeArray {
  static_assert(std::is_trivial_v<T>, "zero bytes must be a value of T");

 public:
  ZeroedLargeArray() = default;
  explicit ZeroedLargeArray(std::size_t n) : data_(LargeArrayAllocator<T>().allocate(n)), size_(n) {
    if (n * sizeof(T) < internal::kHugePageBytes) std::memset(data_, 0, n * sizeof(T));
  }
  ~ZeroedLargeArray() { LargeArrayAllocator<T>().deallocate(data_, size_); }
  ZeroedLargeArray(ZeroedLargeArray&& other) noexcept
      : data_(std::exchange(other.data_, nullptr)), size_(std::exchange(other.size_, 0)) {}
  ZeroedLargeArray& operator=(ZeroedLargeArray&& other) noexcept {
    std::swap(data_, other.data_);
    std::swap(size_, other.size_);
    return *this;
  }
  ZeroedLargeArray(const ZeroedLargeArray&) = delete;
  ZeroedLargeArray& operator=(const ZeroedLargeArray&) = delete;

  T* data() { return data_; }
  const T* data() const { return data_; }
  T* begin() { return data_; }
  const T* begin() const { return data_; }
  std::size_t size() const { return size_; }
  T& operator[](std::size_t i) { return data_[i]; }
  const T& operator[](std::size_t i) const { return data_[i]; }

 private:
  T* data_ = nullptr;
  std::size_t size_ = 0;
};

// Resizes `v` to n elements (new ones zero), touching its fresh storage on
// `threads` threads first. Why: the kernel zeroes a fresh page in the thread
// that first touches it, and on this project's 2-core virtual machine that
// runs at about 1 GB/s: the translation search's spectra and row copies
// (~150 MB on a campus crop pair) were 0.1-0.2 s of a merge's wall time on
// one thread (docs/voxel-merge.md, "One-thread parts shared").
template <typename T>
void ResizeInParallel(LargeVector<T>* v, std::size_t n, int threads) {
  if (n > v->size()) {
    v->reserve(n);
    // [size, n) of the storage holds no element yet: its pages are touched
    // on every thread, and the resize's zeros then land on touched pages.
    auto* fresh = reinterpret_cast<unsigned char*>(v->data() + v->size());
    ParallelRanges((n - v->size()) * sizeof(T), threads, [&](std::size_t begin, std::size_t end) {
      std::memset(fresh + begin, 0, end - begin);
    });
  }
  v->resize(n);
}

// Sets `v` to the n elements at `from`, on `threads` threads
// (ResizeInParallel, then the copy).
template <typename T>
void AssignInParallel(LargeVector<T>* v, const T* from, std::size_t n, int threads) {
  static_assert(std::is_trivially_copyable_v<T>, "copied as bytes");
  ResizeInParallel(v, n, threads);
  ParallelRanges(n, threads, [&](std::size_t begin, std::size_t end) {
    std::memcpy(v->data() + begin, from + begin, (end - begin) * sizeof(T));
  });
}

}  // namespace mapd::voxel

#endif  // MAPD_VOXEL_LARGE_ARRAY_H_
