// A merge on the threads it is given (MergeParams::threads, issue 42 item 5):
// the work splits, the answer does not. Every figure of the outcome and the
// merged map's bytes must equal the single-threaded merge's.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <atomic>
#include <cstdint>
#include <mutex>
#include <random>
#include <set>
#include <string>
#include <vector>

#include "voxel/merge.h"
#include "voxel/parallel.h"
#include "voxel/support/corner_scene.h"
#include "voxel/support/same_outcome.h"
#include "voxel/support/voxel_scene.h"

namespace mapd::voxel {
namespace {

using testing::ExpectSameOutcome;
using testing::Pose;
using testing::RasteriseSubmap;

TEST(ParallelForTest, CallsEveryIndexOnceOnAtMostThatManyWorkers) {
  for (int threads : {0, 1, 2, 5}) {
    std::vector<std::atomic<int>> calls(37);
    std::mutex mutex;
    std::set<std::size_t> workers;
    ParallelFor(calls.size(), threads, [&](std::size_t i, std::size_t worker) {
      ++calls[i];
      const std::lock_guard<std::mutex> lock(mutex);
      workers.insert(worker);
    });
    for (const auto& n : calls) EXPECT_EQ(n.load(), 1) << threads << " threads";
    EXPECT_LE(workers.size(), static_cast<std::size_t>(std::max(threads, 1)));
    EXPECT_LT(*workers.rbegin(), static_cast<std::size_t>(std::max(threads, 1)));
  }
  int none = 0;
  ParallelFor(0, 4, [&](std::size_t, std::size_t) { ++none; });
  EXPECT_EQ(none, 0);

  std::vector<int> covered(300'000, 0);
  ParallelRanges(covered.size(), 3, [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) ++covered[i];
  });
  for (int n : covered) ASSERT_EQ(n, 1);
}

TEST(ParallelSortTest, SortsAsStdSortOnAnyThreadCount) {
  std::mt19937_64 random(7);
  for (const std::size_t n : {std::size_t{0}, std::size_t{1000}, std::size_t{300'001}}) {
    std::vector<std::uint64_t> codes(n);
    for (auto& c : codes) c = random() % 50'000;  // duplicates, as voxel codes have
    std::vector<std::uint64_t> expected = codes;
    std::sort(expected.begin(), expected.end());
    for (int threads : {0, 1, 2, 3, 4, 8}) {
      std::vector<std::uint64_t> sorted = codes;
      ParallelSort(sorted.begin(), sorted.end(), threads);
      ASSERT_EQ(sorted, expected) << n << " values on " << threads << " threads";
    }
  }
}

// Outdoors-like: two crops of the grove, the second turned 30 deg, placed by
// the plan view first (forced here: the crops are small) and then checked by
// the 3D search, so every parallel part runs (the inputs' views, the yaw
// windows, FFTW's threads and the element-wise loops).
TEST(MergeThreadsTest, TheGroveMergesTheSameOnOneTwoAndThreeThreads) {
  const testing::VoxelScene grove = testing::Grove();
  const double res = 0.25;
  const std::string a = RasteriseSubmap(
      grove, Eigen::AlignedBox3d(Eigen::Vector3d(0.5, 0.5, -1), Eigen::Vector3d(24, 39.5, 6)),
      Eigen::Isometry3d::Identity(), res);
  const Eigen::Isometry3d T_a_b = Pose(30, 0, 0, Eigen::Vector3d(14.3, -2.2, 0.4));
  const std::string b = RasteriseSubmap(
      grove, Eigen::AlignedBox3d(Eigen::Vector3d(16, 0.5, -1), Eigen::Vector3d(39.5, 39.5, 6)),
      T_a_b, res);
  MergeParams params;
  params.correlation.plan_view_first_min_cells = 0;
  params.threads = 1;
  const StatusOr<MergeOutcome> one = MergeSubmaps({{1, a}, {2, b}}, params);
  ASSERT_TRUE(one.ok()) << one.status().ToString();
  EXPECT_LT(testing::RotationErrorDeg(one->alignments[1].T_reference_submap, T_a_b), 1.0);
  for (int threads : {2, 3}) {
    params.threads = threads;
    const StatusOr<MergeOutcome> many = MergeSubmaps({{1, a}, {2, b}}, params);
    ASSERT_TRUE(many.ok()) << many.status().ToString();
    SCOPED_TRACE(std::to_string(threads) + " threads");
    ExpectSameOutcome(*one, *many);
  }
}

// Indoors: the 3D search at every yaw (no plan view first), three inputs.
TEST(MergeThreadsTest, ThreeRoomCropsMergeTheSameOnOneAndFourThreads) {
  const testing::VoxelScene room = testing::FurnishedRoom();
  const double res = testing::kRoomResolutionM;
  const std::string a =
      RasteriseSubmap(room, testing::RoomCropX(-0.5, 5.5), Eigen::Isometry3d::Identity(), res);
  const std::string b = RasteriseSubmap(room, testing::RoomCropX(2.5, 8.0),
                                        Pose(-70, 0, 0, Eigen::Vector3d(1.3, 0.4, 0)), res);
  const std::string c = RasteriseSubmap(room, testing::RoomCropX(4.5, 9.5),
                                        Pose(125, 0, 0, Eigen::Vector3d(-2.0, 1.1, 0)), res);
  MergeParams params;
  params.threads = 1;
  const StatusOr<MergeOutcome> one = MergeSubmaps({{1, a}, {2, b}, {3, c}}, params);
  ASSERT_TRUE(one.ok()) << one.status().ToString();
  params.threads = 4;
  const StatusOr<MergeOutcome> many = MergeSubmaps({{1, a}, {2, b}, {3, c}}, params);
  ASSERT_TRUE(many.ok()) << many.status().ToString();
  ExpectSameOutcome(*one, *many);
}

TEST(MergeThreadsTest, ValidateRefusesAThreadCountOutOfRange) {
  MergeParams params;
  params.threads = 0;
  EXPECT_EQ(params.Validate().code(), StatusCode::kInvalidArgument);
  params.threads = 257;
  EXPECT_EQ(params.Validate().code(), StatusCode::kInvalidArgument);
  params.threads = 8;
  EXPECT_TRUE(params.Validate().ok());
}

}  // namespace
}  // namespace mapd::voxel
