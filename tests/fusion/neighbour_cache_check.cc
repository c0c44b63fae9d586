// Every fusion test runs with WallConsolidator's neighbour cache checked: each
// cached list a walk reads is compared with a fresh index search, and a test
// that saw one differ fails. The cache must never change a map.
#include <gtest/gtest.h>

#include "fusion/wall_consolidation.h"

namespace mapd::fusion {
namespace {

class NeighbourCacheCheck : public ::testing::EmptyTestEventListener {
  void OnTestStart(const ::testing::TestInfo&) override {
    WallConsolidator::SetVerifyNeighbourCache(true);
    at_start_ = WallConsolidator::neighbour_cache_mismatches();
  }
  void OnTestEnd(const ::testing::TestInfo& info) override {
    const size_t mismatches = WallConsolidator::neighbour_cache_mismatches() - at_start_;
    if (mismatches != 0) {
      ADD_FAILURE() << info.name() << ": " << mismatches
                    << " cached neighbour lists differed from a fresh search";
    }
  }
  size_t at_start_ = 0;
};

// Registered before main() runs the tests (gtest_main keeps registered listeners).
const bool kRegistered = [] {
  ::testing::UnitTest::GetInstance()->listeners().Append(new NeighbourCacheCheck);
  return true;
}();

}  // namespace
}  // namespace mapd::fusion
