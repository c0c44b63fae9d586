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
