// The engine's grid index (fusion/grid_index.h): its open-addressing cell
// table against std::map under random inserts and erases, and the grid's
// queries against brute force.
#include "fusion/grid_index.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <map>
#include <random>
#include <utility>
#include <vector>

namespace mapd::fusion {
namespace {

using geometry::Segment2;
using geometry::Vec2;

TEST(CellTableTest, MatchesAMapThroughGrowthAndBackwardShiftErase) {
  CellTable<int> table;
  std::map<std::pair<int64_t, int64_t>, int> reference;
  std::mt19937 rng(7);
  // A small key range: long probe runs, wrap-around and many erase shifts.
  std::uniform_int_distribution<int64_t> coord(-20, 20);
  for (int step = 0; step < 20000; ++step) {
    const CellKey key{coord(rng), coord(rng)};
    const auto ref_key = std::make_pair(key.x, key.y);
    if (rng() % 3 == 0 && reference.count(ref_key) != 0) {
      table.Find(key)->clear();
      table.Erase(key);
      reference.erase(ref_key);
    } else {
      table.FindOrAdd(key).push_back(step);
      reference[ref_key] = step;
    }
    ASSERT_EQ(table.size(), reference.size());
  }
  for (int64_t x = -21; x <= 21; ++x) {
    for (int64_t y = -21; y <= 21; ++y) {
      const std::vector<int>* items = table.Find({x, y});
      auto it = reference.find({x, y});
      ASSERT_EQ(items != nullptr, it != reference.end()) << x << "," << y;
      if (items != nullptr) {
        EXPECT_EQ(items->back(), it->second);
      }
    }
  }
  size_t visited = 0;
  table.ForEach([&](const CellKey& key, const std::vector<int>& items) {
    ++visited;
    EXPECT_EQ(items.back(), reference.at({key.x, key.y}));
  });
  EXPECT_EQ(visited, reference.size());
}

TEST(UniformGridTest, QueriesFindWhatBruteForceFindsAfterErases) {
  UniformGrid<int> grid(2.0);
  std::vector<std::pair<Vec2, int>> filed;
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> xy(-50.0, 50.0);
  for (int i = 0; i < 3000; ++i) {
    const Vec2 p(xy(rng), xy(rng));
    grid.Insert(p, i);
    filed.emplace_back(p, i);
  }
  for (int i = 0; i < 3000; i += 2) {
    grid.EraseIf(filed[i].first, [i](int item) { return item == i; });
  }
  for (int q = 0; q < 200; ++q) {
    const Segment2 s{Vec2(xy(rng), xy(rng)), Vec2(xy(rng), xy(rng))};
    const double radius = 3.0;
    std::vector<int> found;
    grid.ForEachNearSegment(s, radius, [&](int item) { found.push_back(item); });
    std::sort(found.begin(), found.end());
    // Every item within radius of s is found; nothing erased is.
    for (int i = 1; i < 3000; i += 2) {
      if (geometry::PointSegmentDistance(filed[i].first, s) <= radius) {
        EXPECT_TRUE(std::binary_search(found.begin(), found.end(), i)) << q << " " << i;
      }
    }
    for (int item : found) EXPECT_EQ(item % 2, 1);
  }
}

}  // namespace
}  // namespace mapd::fusion
