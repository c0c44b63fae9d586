// PreparedSubmaps, the merge runner's views kept between merges: least
// recently used out beyond the budget, one merge at a time per view, and a
// deleted submap's (or a closed map's) view never kept again.
#include "service/prepared_submaps.h"

#include <gtest/gtest.h>

#include <chrono>
#include <memory>
#include <string>
#include <vector>

#include "common/octomap_scenes.h"
#include "service/merge_runner.h"
#include "service/voxel_merge.h"

namespace mapd::testing {
namespace {

using service::PreparedKey;
using service::PreparedSubmaps;

class PreparedSubmapsTest : public ::testing::Test {
 protected:
  // Views of one small room submap under ids 1..count (equal sizes).
  std::vector<PreparedSubmaps::View> Views(uint64_t count) {
    const std::string bt = RoomSubmap(RoomScene(), 0, 3, Eigen::Isometry3d::Identity());
    std::vector<voxel::SubmapInput> inputs;
    for (uint64_t id = 1; id <= count; ++id) inputs.push_back({id, bt});
    auto views = service::PrepareVoxelSubmaps(inputs, voxel::MergeParams());
    EXPECT_TRUE(views.ok()) << views.status().ToString();
    return views.ok() ? *views : std::vector<PreparedSubmaps::View>();
  }
  static std::size_t Bytes(const PreparedSubmaps::View& view) {
    return service::PreparedVoxelSubmapBytes(*view);
  }
};

TEST_F(PreparedSubmapsTest, KeepsTheMostRecentlyUsedWithinTheBudget) {
  auto views = Views(3);
  ASSERT_EQ(views.size(), 3u);
  const std::size_t one = Bytes(views[0]);
  ASSERT_GT(one, 0u);
  PreparedSubmaps cache(2 * one + one / 2);  // room for two
  ASSERT_TRUE(cache.enabled());
  cache.Put({1, 1}, views[0]);
  cache.Put({1, 2}, views[1]);
  EXPECT_EQ(cache.size(), 2u);
  EXPECT_EQ(cache.bytes(), 2 * one);

  // Taken: out of the cache (one merge at a time), still known.
  PreparedSubmaps::View taken = cache.Take({1, 1});
  ASSERT_EQ(taken, views[0]);
  EXPECT_EQ(cache.Take({1, 1}), nullptr);
  EXPECT_TRUE(cache.Has({1, 1}));
  EXPECT_EQ(cache.size(), 1u);
  cache.Put({1, 1}, taken);  // back, and now the most recently used

  cache.Put({1, 3}, views[2]);  // evicts submap 2, the least recently used
  EXPECT_EQ(cache.size(), 2u);
  EXPECT_FALSE(cache.Has({1, 2}));
  EXPECT_EQ(cache.Take({1, 2}), nullptr);
  EXPECT_TRUE(cache.Has({1, 1}));
  EXPECT_TRUE(cache.Has({1, 3}));
  EXPECT_LE(cache.bytes(), 2 * one + one / 2);
  // Another map's submap 3 is another view.
  EXPECT_FALSE(cache.Has({2, 3}));
}

TEST_F(PreparedSubmapsTest, ADeletedSubmapOrClosedMapIsNeverKeptAgain) {
  auto views = Views(3);
  ASSERT_EQ(views.size(), 3u);
  PreparedSubmaps cache(std::size_t{1} << 30);
  cache.Put({1, 1}, views[0]);
  cache.Put({1, 2}, views[1]);
  cache.Put({2, 1}, views[2]);

  // Deleted while a merge holds it: not put back.
  PreparedSubmaps::View taken = cache.Take({1, 1});
  ASSERT_NE(taken, nullptr);
  cache.Forget({1, 1});
  cache.Put({1, 1}, taken);
  EXPECT_FALSE(cache.Has({1, 1}));
  EXPECT_EQ(cache.size(), 2u);

  cache.ForgetOwner(1);
  EXPECT_FALSE(cache.Has({1, 2}));
  cache.Put({1, 2}, views[1]);  // a preparation that ends after the map closed
  EXPECT_FALSE(cache.Has({1, 2}));
  EXPECT_TRUE(cache.Has({2, 1}));  // the other map's stays
  EXPECT_EQ(cache.size(), 1u);
  EXPECT_EQ(cache.bytes(), Bytes(views[2]));
}

TEST_F(PreparedSubmapsTest, AViewLargerThanTheBudgetIsNotKept) {
  auto views = Views(1);
  ASSERT_EQ(views.size(), 1u);
  PreparedSubmaps small(Bytes(views[0]) / 2);
  small.Put({1, 1}, views[0]);
  EXPECT_FALSE(small.Has({1, 1}));
  EXPECT_EQ(small.bytes(), 0u);
  EXPECT_FALSE(PreparedSubmaps(0).enabled());
}

// The runner hands a merge's outcome over without its merged tree, which the
// library returns with it (voxel/merge.h, MergeOutcome::merged_tree): the
// worker frees the tree after waking the handler (a campus pair's takes
// ~0.15 s), so the handler does not wait for that before it stores the merge.
TEST(MergeRunnerTest, HandsTheOutcomeOverAndFreesTheMergedTreeItself) {
  const RoomScene room;
  const std::string a = RoomSubmap(room, 0, 8, Eigen::Isometry3d::Identity());
  const std::string b =
      RoomSubmap(room, 3, 11, YawTranslation(M_PI / 2, Eigen::Vector3d(2.0, -1.0, 0.0)));
  voxel::MergeParams params;
  const auto library = service::MergeVoxelSubmaps({{1, a}, {2, b}}, params, {});
  ASSERT_TRUE(library.ok()) << library.status().ToString();
  EXPECT_NE(library->merged_tree, nullptr);

  service::MergeRunner runner(1, 1, /*prepared_budget_bytes=*/0);
  auto job = runner.Submit(runner.NewOwner(), {1, 2}, {a, b}, params);
  ASSERT_TRUE(job.ok()) << job.status().ToString();
  std::vector<service::MergeProgressEvent> events;
  while (!(*job)->Wait(std::chrono::milliseconds(50), &events)) {
  }
  const StatusOr<voxel::MergeOutcome> outcome = (*job)->TakeResult();
  ASSERT_TRUE(outcome.ok()) << outcome.status().ToString();
  EXPECT_EQ(outcome->merged_tree, nullptr);
  EXPECT_TRUE(outcome->merged_bt == library->merged_bt);
}

}  // namespace
}  // namespace mapd::testing
