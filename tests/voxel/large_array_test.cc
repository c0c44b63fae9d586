// LargeArray: huge-page alignment and unmapping of large blocks, zeroed arrays
// that touch only what is written, and impossible sizes.
#include "voxel/large_array.h"

#include <gtest/gtest.h>
#include <sys/mman.h>
#include <unistd.h>

#include <cstdint>
#include <fstream>
#include <new>
#include <numeric>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

namespace mapd::voxel {
namespace {

std::uintptr_t Address(const void* p) { return reinterpret_cast<std::uintptr_t>(p); }

// Whether /proc/self/maps has a mapping that holds the address `p`.
bool IsMapped(const void* p) {
  std::ifstream maps("/proc/self/maps");
  std::string line;
  while (std::getline(maps, line)) {
    std::istringstream range(line);
    std::uintptr_t begin = 0, end = 0;
    char dash = 0;
    range >> std::hex >> begin >> dash >> end;
    if (begin <= Address(p) && Address(p) < end) return true;
  }
  return false;
}

TEST(LargeArrayTest, LargeBlocksAreHugePageAlignedAndHoldTheirValues) {
  for (const std::size_t n : {std::size_t{1} << 19, (std::size_t{3} << 20) + 7}) {
    LargeVector<float> v(n, 1.5F);
    EXPECT_EQ(Address(v.data()) % internal::kHugePageBytes, 0U) << n;
    std::iota(v.begin(), v.end(), 0.0F);
    EXPECT_EQ(v[n - 1], static_cast<float>(n - 1));
    const LargeVector<float> copy = v;  // copies allocate too
    EXPECT_EQ(copy, v);
  }
}

TEST(LargeArrayTest, SmallBlocksComeFromTheHeapAligned) {
  LargeVector<std::uint8_t> v(100, 7);
  EXPECT_EQ(Address(v.data()) % 64, 0U);
  EXPECT_EQ(v[99], 7);
  v.resize(1);  // and grow again, through every size class
  for (int i = 0; i < 5'000'000; ++i) v.push_back(static_cast<std::uint8_t>(i));
  EXPECT_EQ(v.size(), 5'000'001U);
  EXPECT_EQ(v.back(), static_cast<std::uint8_t>(4'999'999));
}

// A size no system has (or one that would wrap when rounded to huge pages)
// is refused as operator new refuses it, never handed a small block.
TEST(LargeArrayTest, ImpossibleSizesThrowBadAlloc) {
  LargeArrayAllocator<float> floats;
  EXPECT_THROW(floats.allocate(static_cast<std::size_t>(-1) / sizeof(float) + 1),
               std::bad_array_new_length);
  EXPECT_THROW(internal::AllocateLarge(static_cast<std::size_t>(-1) - 10), std::bad_alloc);
  EXPECT_THROW(internal::AllocateLarge(std::size_t{1} << 60), std::bad_alloc);
}

// A long-running server must get a merge's peak back: a freed large block is
// unmapped at once, not kept in malloc's heap.
TEST(LargeArrayTest, AFreedLargeBlockIsUnmapped) {
  const void* data = nullptr;
  {
    LargeVector<double> v(std::size_t{1} << 20);
    data = v.data();
    ASSERT_TRUE(IsMapped(data));
  }
  EXPECT_FALSE(IsMapped(data));
}

// Zeros that are never written cost no memory: only the pages a grid's
// content touches are resident (mincore: 4 KiB pages, or 2 MiB ones under
// transparent huge pages).
TEST(LargeArrayTest, ZeroedArraysAreZerosAndTouchOnlyWhatIsWritten) {
  const std::size_t page = static_cast<std::size_t>(sysconf(_SC_PAGESIZE));
  const std::size_t bytes = std::size_t{64} << 20;
  ZeroedLargeArray<float> big(bytes / sizeof(float));
  ASSERT_EQ(big.size(), bytes / sizeof(float));
  big[12345] = 2.0F;  // one page (or one huge page) written
  std::vector<unsigned char> resident(bytes / page);
  ASSERT_EQ(mincore(big.data(), bytes, resident.data()), 0);
  std::size_t pages = 0;
  for (unsigned char r : resident) pages += r & 1U;
  EXPECT_GE(pages, 1U);
  EXPECT_LE(pages * page, internal::kHugePageBytes);
  for (std::size_t i = 0; i < big.size(); i += 4099) EXPECT_EQ(big[i], i == 12345 ? 2.0F : 0.0F);
  EXPECT_EQ(big[12345], 2.0F);

  // Small ones come from the heap, zeroed all the same; moves hand over the block.
  ZeroedLargeArray<std::uint8_t> small(1000);
  for (std::size_t i = 0; i < small.size(); ++i) ASSERT_EQ(small[i], 0) << i;
  small[999] = 9;
  ZeroedLargeArray<std::uint8_t> moved(std::move(small));
  EXPECT_EQ(moved.size(), 1000U);
  EXPECT_EQ(moved[999], 9);
  moved = ZeroedLargeArray<std::uint8_t>(3);
  EXPECT_EQ(moved.size(), 3U);
  EXPECT_EQ(moved[2], 0);
}

// Empty and impossible sizes: an empty array, and bad_alloc as LargeVector
// (never a write through a null or short block).
TEST(LargeArrayTest, ZeroedArraysOfNoneOrImpossibleSizes) {
  const ZeroedLargeArray<float> none(0);
  EXPECT_EQ(none.size(), 0U);
  EXPECT_THROW(ZeroedLargeArray<float>(static_cast<std::size_t>(-1) / sizeof(float) + 1),
               std::bad_array_new_length);
  EXPECT_THROW(ZeroedLargeArray<std::uint8_t>(std::size_t{1} << 60), std::bad_alloc);
}

}  // namespace
}  // namespace mapd::voxel
