// PackedKeySet against std::set: contents, insertion order, empty and cleared sets.
#include "voxel/packed_key_set.h"

#include <gtest/gtest.h>

#include <cstdint>
#include <random>
#include <set>
#include <vector>

namespace mapd::voxel {
namespace {

// Against std::set: the same members after many inserts with repeats (the
// table grows several times on the way), the same answers for absent keys,
// and iteration in the order of first insertion.
TEST(PackedKeySetTest, HoldsWhatASetHoldsInInsertionOrder) {
  std::mt19937_64 rng(3);
  // 48-bit keys in a few small fields, as packed voxel keys are: many share
  // their low bits, which a hash on the low bits alone would pile up.
  std::uniform_int_distribution<std::uint64_t> axis(0, 300);
  PackedKeySet set;
  std::set<std::uint64_t> want;
  std::vector<std::uint64_t> first_seen;
  for (int i = 0; i < 60000; ++i) {
    const std::uint64_t key = axis(rng) | (axis(rng) << 16) | ((axis(rng) % 4) << 32);
    const bool fresh = want.insert(key).second;
    EXPECT_EQ(set.insert(key), fresh);
    if (fresh) first_seen.push_back(key);
  }
  EXPECT_EQ(set.size(), want.size());
  EXPECT_LT(set.size(), 60000U);  // there were repeats
  EXPECT_EQ(set.keys(), first_seen);
  for (int i = 0; i < 20000; ++i) {
    const std::uint64_t key = axis(rng) | (axis(rng) << 16) | ((axis(rng) % 8) << 32);
    EXPECT_EQ(set.contains(key), want.count(key) > 0) << key;
  }
}

TEST(PackedKeySetTest, EmptyReservedAndClearedSetsHoldNothing) {
  PackedKeySet set;
  EXPECT_TRUE(set.empty());
  EXPECT_FALSE(set.contains(0));
  set.reserve(1000);
  EXPECT_FALSE(set.contains(0));
  EXPECT_TRUE(set.insert(0));
  EXPECT_TRUE(set.insert((std::uint64_t{1} << 48) - 1));
  EXPECT_TRUE(set.contains(0));
  EXPECT_TRUE(set.contains((std::uint64_t{1} << 48) - 1));
  EXPECT_FALSE(set.contains(1));
  set.clear();
  EXPECT_TRUE(set.empty());
  EXPECT_FALSE(set.contains(0));
  EXPECT_TRUE(set.insert(7));
  EXPECT_EQ(set.keys(), std::vector<std::uint64_t>{7});
}

}  // namespace
}  // namespace mapd::voxel
