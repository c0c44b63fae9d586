#include "voxel/large_array.h"

#include <gtest/gtest.h>

#include <cstdint>
#include <fstream>
#include <new>
#include <numeric>
#include <sstream>
#include <string>

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

}  // namespace
}  // namespace mapd::voxel
