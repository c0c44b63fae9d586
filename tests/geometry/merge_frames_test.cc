// The frame rule of an accepted merge (geometry/merge_frames.h).
#include "geometry/merge_frames.h"

#include <gtest/gtest.h>

#include <cmath>

namespace mapd::geometry {
namespace {

Rigid3 Yaw(double deg, const Eigen::Vector3d& t) {
  return {Eigen::Quaterniond(Eigen::AngleAxisd(deg * M_PI / 180, Eigen::Vector3d::UnitZ())), t};
}

void ExpectNear(const Rigid3& a, const Rigid3& b) {
  EXPECT_LT((a.translation - b.translation).norm(), 1e-9);
  EXPECT_LT(a.rotation.angularDistance(b.rotation), 1e-9);
}

TEST(MergeFramesTest, AnIslandLandsAtTheMapOriginAndTiesItsSessions) {
  const Rigid3 T_ref_b = Yaw(90, {2, -1, 0});
  const StatusOr<MergeFrames> f =
      FramesOfMerge({{1, 10, {}, {}}, {2, 20, {}, {}}}, {Rigid3::Identity(), T_ref_b});
  ASSERT_TRUE(f.ok()) << f.status().ToString();
  ASSERT_EQ(f->placements.size(), 2u);
  ExpectNear(f->placements[0].second, Rigid3::Identity());
  ExpectNear(f->placements[1].second, T_ref_b);
  ASSERT_EQ(f->ties.size(), 2u);
  EXPECT_EQ(f->ties[0].first, 10);
  EXPECT_EQ(f->ties[1].first, 20);
  ExpectNear(f->ties[1].second, T_ref_b);
}

TEST(MergeFramesTest, ATiedInputFixesTheReferenceAndIsNotTiedAgain) {
  // Input 1's session is tied at T_map_s; input 0 (the reference) is not.
  const Rigid3 T_map_s = Yaw(30, {5, 5, 0});
  const Rigid3 T_ref_1 = Yaw(-45, {1, 2, 0});
  const StatusOr<MergeFrames> f =
      FramesOfMerge({{1, 10, {}, {}}, {2, 20, T_map_s, {}}}, {Rigid3::Identity(), T_ref_1});
  ASSERT_TRUE(f.ok());
  const Rigid3 T_map_ref = T_map_s * T_ref_1.inverse();
  ExpectNear(f->placements[0].second, T_map_ref);
  ExpectNear(f->placements[1].second, T_map_s);
  ASSERT_EQ(f->ties.size(), 1u);  // session 20 is tied already
  EXPECT_EQ(f->ties[0].first, 10);
  ExpectNear(f->ties[0].second, T_map_ref);
}

TEST(MergeFramesTest, AnEarlierPlacementFixesASessionlessInputAndASessionIsTiedOnce) {
  const Rigid3 T_map_placed = Yaw(10, {-3, 0, 1});
  const Rigid3 T_ref_1 = Yaw(5, {0.5, 0, 0});
  const Rigid3 T_ref_2 = Yaw(-5, {0, 0.5, 0});
  // Input 0: no session, placed by an earlier merge; inputs 1 and 2 share
  // session 7 (a later placement of a sessionless input is not its pose:
  // only T_map_submap counts for session 0).
  const StatusOr<MergeFrames> f =
      FramesOfMerge({{1, 0, {}, T_map_placed}, {2, 7, {}, {}}, {3, 7, {}, Yaw(99, {9, 9, 9})}},
                    {Rigid3::Identity(), T_ref_1, T_ref_2});
  ASSERT_TRUE(f.ok());
  ExpectNear(f->placements[0].second, T_map_placed);
  ExpectNear(f->placements[2].second, T_map_placed * T_ref_2);
  ASSERT_EQ(f->ties.size(), 1u);
  EXPECT_EQ(f->ties[0].first, 7);
  ExpectNear(f->ties[0].second, T_map_placed * T_ref_1);
}

TEST(MergeFramesTest, RefusesMismatchedLists) {
  EXPECT_EQ(FramesOfMerge({}, {}).status().code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(FramesOfMerge({{1, 0, {}, {}}}, {}).status().code(), StatusCode::kInvalidArgument);
}

}  // namespace
}  // namespace mapd::geometry
