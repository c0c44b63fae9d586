// SupportCounter: distinct observations counted exactly up to its cap, then
// by count alone.
#include "fusion/support_counter.h"

#include <gtest/gtest.h>

namespace mapd::fusion {
namespace {

TEST(SupportCounterTest, CountsDistinctObservationsExactlyUpToTheCap) {
  SupportCounter c;
  for (ObservationId id : {5u, 3u, 5u, 9u, 3u}) c.Add(id, 10);
  EXPECT_EQ(c.count(), 3u);
  EXPECT_TRUE(c.exact());
  SupportCounter other;
  for (ObservationId id : {9u, 11u, 1u}) other.Add(id, 10);
  c.Merge(std::move(other), 10);
  EXPECT_EQ(c.count(), 5u);  // {1, 3, 5, 9, 11}
  EXPECT_EQ(c.ids(), (std::vector<ObservationId>{1, 3, 5, 9, 11}));
}

// Merge from a const counter (walls merge their pieces' counters in place)
// leaves exactly the state Merge of a moved copy leaves, on every shape of
// two id lists: empty, disjoint either way round, interleaved, shared ids,
// and past the cap on either side.
TEST(SupportCounterTest, MergeFromConstEqualsMergeOfACopy) {
  const auto counter = [](std::vector<ObservationId> ids, uint32_t cap) {
    SupportCounter c;
    for (ObservationId id : ids) c.Add(id, cap);
    return c;
  };
  const std::vector<std::vector<ObservationId>> lists = {
      {}, {1, 2, 3}, {7, 8}, {2, 5, 9}, {3}, {1, 2, 3, 4, 5, 6}, {10, 20, 30, 40}};
  for (uint32_t cap : {4u, 6u, SupportCounter::kUnlimited}) {
    for (const auto& a : lists) {
      for (const auto& b : lists) {
        SupportCounter moved = counter(a, cap);
        SupportCounter copy = counter(b, cap);
        moved.Merge(std::move(copy), cap);
        SupportCounter in_place = counter(a, cap);
        const SupportCounter other = counter(b, cap);
        in_place.Merge(other, cap);
        EXPECT_EQ(in_place.count(), moved.count());
        EXPECT_EQ(in_place.exact(), moved.exact());
        EXPECT_EQ(in_place.ids(), moved.ids());
        EXPECT_EQ(in_place.last(), moved.last());
        EXPECT_EQ(in_place.saturated_count(), moved.saturated_count());
        EXPECT_EQ(other.ids(), counter(b, cap).ids()) << "the const counter changed";
      }
    }
  }
}

TEST(SupportCounterTest, PastTheCapKeepsCountingWithoutIds) {
  SupportCounter c;
  for (ObservationId id = 1; id <= 4; ++id) c.Add(id, 3);
  EXPECT_FALSE(c.exact());
  EXPECT_EQ(c.count(), 4u);
  EXPECT_TRUE(c.ids().empty());
  c.Add(5, 3);
  c.Add(5, 3);  // a second feature of the same observation counts once
  EXPECT_EQ(c.count(), 5u);
  // Two clusters that both took a feature of observation 6 merge: 6 counts once.
  c.Add(6, 3);
  SupportCounter other;
  other.Add(2, 3);
  other.Add(6, 3);
  c.Merge(std::move(other), 3);
  EXPECT_EQ(c.count(), 7u);  // 6 + 2 - 1: observation 2 counts twice (documented)
}

TEST(SupportCounterTest, UnlimitedCapIsExactForever) {
  SupportCounter c;
  for (ObservationId id = 1000; id > 0; --id) c.Add(id, SupportCounter::kUnlimited);
  EXPECT_TRUE(c.exact());
  EXPECT_EQ(c.count(), 1000u);
}

}  // namespace
}  // namespace mapd::fusion
