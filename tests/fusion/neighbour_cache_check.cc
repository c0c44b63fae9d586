// Every fusion test runs with WallConsolidator's caches checked: each cached
// neighbour list a walk reads is compared with a fresh index search, and each
// touched piece's piercing (kept without a fresh check while its samples stay
// within their clearance, piercing.h) with a fresh check; a test that saw one
// differ fails. The caches must never change a map.
#include <gtest/gtest.h>

#include "fusion/wall_consolidation.h"

namespace mapd::fusion {
namespace {

class NeighbourCacheCheck : public ::testing::EmptyTestEventListener {
  void OnTestStart(const ::testing::TestInfo&) override {
    WallConsolidator::SetVerifyNeighbourCache(true);
    at_start_ = WallConsolidator::neighbour_cache_mismatches();
    piercing_at_start_ = WallConsolidator::piercing_mismatches();
  }
  void OnTestEnd(const ::testing::TestInfo& info) override {
    const size_t mismatches = WallConsolidator::neighbour_cache_mismatches() - at_start_;
    if (mismatches != 0) {
      ADD_FAILURE() << info.name() << ": " << mismatches
                    << " cached neighbour lists differed from a fresh search";
    }
    const size_t piercing = WallConsolidator::piercing_mismatches() - piercing_at_start_;
    if (piercing != 0) {
      ADD_FAILURE() << info.name() << ": " << piercing
                    << " pieces' piercing differed from a fresh check";
    }
  }
  size_t at_start_ = 0;
  size_t piercing_at_start_ = 0;
};

// Registered before main() runs the tests (gtest_main keeps registered listeners).
const bool kRegistered = [] {
  ::testing::UnitTest::GetInstance()->listeners().Append(new NeighbourCacheCheck);
  return true;
}();

}  // namespace
}  // namespace mapd::fusion
