// Prepared submaps (merge.h PrepareSubmaps, MergePreparedSubmaps): a merge
// from views read earlier, and kept for the next merge, decides exactly as a
// merge from the bytes; the views' memory is measured; bad input is named.
#include <gtest/gtest.h>
#include <octomap/OcTree.h>

#include <Eigen/Geometry>
#include <memory>
#include <string>
#include <vector>

#include "voxel/merge.h"
#include "voxel/octree_reader.h"
#include "voxel/support/same_outcome.h"
#include "voxel/support/voxel_scene.h"

namespace mapd::voxel {
namespace {

using testing::ExpectSameOutcome;
using testing::Pose;
using testing::RasteriseSubmap;

class PreparedSubmapTest : public ::testing::Test {
 protected:
  void SetUp() override {
    const testing::VoxelScene room = testing::FurnishedRoom();
    const double res = testing::kRoomResolutionM;
    a_ = RasteriseSubmap(room, testing::RoomCropX(-0.5, 5.5), Eigen::Isometry3d::Identity(), res);
    b_ = RasteriseSubmap(room, testing::RoomCropX(2.5, 8.0),
                         Pose(-70, 0, 0, Eigen::Vector3d(1.3, 0.4, 0)), res);
    c_ = RasteriseSubmap(room, testing::RoomCropX(4.5, 9.5),
                         Pose(125, 0, 0, Eigen::Vector3d(-2.0, 1.1, 0)), res);
    params_.threads = 2;
  }
  std::string a_, b_, c_;
  MergeParams params_;
};

TEST_F(PreparedSubmapTest, MergesAsFromTheBytesAndAgainFromTheKeptViews) {
  const StatusOr<MergeOutcome> from_bytes = MergeSubmaps({{1, a_}, {2, b_}, {3, c_}}, params_);
  ASSERT_TRUE(from_bytes.ok()) << from_bytes.status().ToString();
  ASSERT_EQ(from_bytes->alignments.size(), 3u);

  auto views = PrepareSubmaps({{1, a_}, {2, b_}, {3, c_}}, params_);
  ASSERT_TRUE(views.ok()) << views.status().ToString();
  ASSERT_EQ(views->size(), 3u);
  std::vector<std::size_t> bytes_before;
  for (std::size_t i = 0; i < views->size(); ++i) {
    EXPECT_EQ((*views)[i]->id(), i + 1);
    bytes_before.push_back((*views)[i]->MemoryBytes());
    EXPECT_GT(bytes_before.back(), a_.size()) << "a view holds the tree and the grid";
  }
  const StatusOr<MergeOutcome> prepared = MergePreparedSubmaps(*views, params_);
  ASSERT_TRUE(prepared.ok()) << prepared.status().ToString();
  EXPECT_EQ(prepared->times.reading_s, 0.0);
  ExpectSameOutcome(*from_bytes, *prepared);
  // The merged tree comes with the outcome, for the caller to free when it
  // suits: the tree merged_bt was written from.
  ASSERT_NE(prepared->merged_tree, nullptr);
  const auto written =
      WriteBinaryOctree(*static_cast<const octomap::OcTree*>(prepared->merged_tree.get()));
  ASSERT_TRUE(written.ok()) << written.status().ToString();
  EXPECT_TRUE(*written == prepared->merged_bt);
  // The views keep what the merge computed of them (A's indexes at least)...
  EXPECT_GT((*views)[0]->MemoryBytes(), bytes_before[0]);
  for (std::size_t i = 0; i < views->size(); ++i)
    EXPECT_GE((*views)[i]->MemoryBytes(), bytes_before[i]);
  // ... and the next merges from them, on one thread, decide as merges from
  // the bytes: a pair of them, and the reverse pair (which B as the
  // reference refuses: its reason must be the same too).
  params_.threads = 1;
  const StatusOr<MergeOutcome> again = MergePreparedSubmaps({(*views)[0], (*views)[1]}, params_);
  ASSERT_TRUE(again.ok()) << again.status().ToString();
  const StatusOr<MergeOutcome> again_from_bytes = MergeSubmaps({{1, a_}, {2, b_}}, params_);
  ASSERT_TRUE(again_from_bytes.ok()) << again_from_bytes.status().ToString();
  ExpectSameOutcome(*again_from_bytes, *again);
  const StatusOr<MergeOutcome> reverse = MergePreparedSubmaps({(*views)[1], (*views)[0]}, params_);
  const StatusOr<MergeOutcome> reverse_from_bytes = MergeSubmaps({{2, b_}, {1, a_}}, params_);
  ASSERT_EQ(reverse.ok(), reverse_from_bytes.ok());
  if (reverse.ok()) {
    ExpectSameOutcome(*reverse_from_bytes, *reverse);
  } else {
    EXPECT_EQ(reverse.status().ToString(), reverse_from_bytes.status().ToString());
  }
}

TEST_F(PreparedSubmapTest, BadInputIsNamed) {
  auto views = PrepareSubmaps({{1, a_}, {7, "not an octree"}}, params_);
  ASSERT_FALSE(views.ok());
  EXPECT_EQ(views.status().code(), StatusCode::kInvalidArgument);
  EXPECT_NE(views.status().message().find("submap 7"), std::string::npos)
      << views.status().ToString();

  auto good = PrepareSubmaps({{1, a_}, {2, b_}}, params_);
  ASSERT_TRUE(good.ok()) << good.status().ToString();
  const auto one = MergePreparedSubmaps({(*good)[0]}, params_);
  EXPECT_EQ(one.status().code(), StatusCode::kInvalidArgument);
  const auto twice = MergePreparedSubmaps({(*good)[0], (*good)[0]}, params_);
  EXPECT_EQ(twice.status().code(), StatusCode::kInvalidArgument);
  EXPECT_NE(twice.status().message().find("submap 1 is given twice"), std::string::npos)
      << twice.status().ToString();
  const auto missing = MergePreparedSubmaps({(*good)[0], nullptr}, params_);
  EXPECT_EQ(missing.status().code(), StatusCode::kInvalidArgument);
  MergeParams bad = params_;
  bad.threads = 0;
  EXPECT_EQ(PrepareSubmaps({{1, a_}}, bad).status().code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(MergePreparedSubmaps(*good, bad).status().code(), StatusCode::kInvalidArgument);
}

}  // namespace
}  // namespace mapd::voxel
