// voxel::ExtendGlobalMap (global_map.h): the union of placed submaps, built
// at once or member by member with the same result, and clear errors.
#include "voxel/global_map.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <atomic>
#include <string>

#include "voxel/support/lattice_copy.h"
#include "voxel/support/voxel_scene.h"

namespace mapd::voxel {
namespace {

using testing::kRoomResolutionM;

// The west and east halves of the furnished room, each in a frame of its own
// moved by a lattice pose (so that the union can be compared voxel for
// voxel with the room cut in one piece).
struct Halves {
  std::string west, east, whole;
  Eigen::Isometry3d T_map_west, T_map_east;
};

Halves RoomHalves() {
  const auto room = testing::FurnishedRoom();
  Halves h;
  h.whole = testing::RasteriseSubmap(room, testing::RoomCropX(-0.5, 9.5),
                                     Eigen::Isometry3d::Identity(), kRoomResolutionM);
  const std::string west = testing::RasteriseSubmap(
      room, testing::RoomCropX(-0.5, 5.0), Eigen::Isometry3d::Identity(), kRoomResolutionM);
  const std::string east = testing::RasteriseSubmap(
      room, testing::RoomCropX(5.0, 9.5), Eigen::Isometry3d::Identity(), kRoomResolutionM);
  testing::LatticeMove to_west, to_east;
  to_west.shift_voxels = Eigen::Vector3i(3, -2, 0);
  to_east.rotation << 0, -1, 0, 1, 0, 0, 0, 0, 1;
  to_east.shift_voxels = Eigen::Vector3i(-40, 7, 1);
  h.west = testing::MoveByLattice(west, to_west);
  h.east = testing::MoveByLattice(east, to_east);
  // Where each sits in the map (= the room's) frame: back by its move.
  h.T_map_west = to_west.Transform(kRoomResolutionM).inverse();
  h.T_map_east = to_east.Transform(kRoomResolutionM).inverse();
  return h;
}

TEST(GlobalMapTest, TheUnionOfPlacedHalvesIsTheWhole) {
  const Halves h = RoomHalves();
  auto all = ExtendGlobalMap("", {{1, h.T_map_west, h.west}, {2, h.T_map_east, h.east}}, {});
  ASSERT_TRUE(all.ok()) << all.status().ToString();
  EXPECT_EQ(all->resolution_m, kRoomResolutionM);
  // The halves were cut from one scene: together, the scene cut at once
  // (outside both crops' shared seam nothing differs).
  const testing::VoxelStates whole = testing::StatesOf(h.whole);
  const testing::VoxelStates got = testing::StatesOf(all->bt);
  long occupied_whole = 0, occupied_got = 0;
  for (const auto& [key, occupied] : whole) occupied_whole += occupied ? 1 : 0;
  for (const auto& [key, occupied] : got) occupied_got += occupied ? 1 : 0;
  EXPECT_EQ(occupied_got, occupied_whole);
  EXPECT_EQ(all->occupied_voxels, static_cast<uint64_t>(occupied_got));

  // Member by member: the same map.
  auto first = ExtendGlobalMap("", {{1, h.T_map_west, h.west}}, {});
  ASSERT_TRUE(first.ok()) << first.status().ToString();
  auto second = ExtendGlobalMap(first->bt, {{2, h.T_map_east, h.east}}, {});
  ASSERT_TRUE(second.ok()) << second.status().ToString();
  EXPECT_EQ(testing::DescribeDifference(testing::StatesOf(second->bt), got), "");
}

TEST(GlobalMapTest, BadInputIsAClearError) {
  const Halves h = RoomHalves();
  auto bad = ExtendGlobalMap("", {{1, h.T_map_west, h.west}, {7, h.T_map_east, "not a map"}}, {});
  ASSERT_FALSE(bad.ok());
  EXPECT_EQ(bad.status().code(), StatusCode::kInvalidArgument);
  EXPECT_NE(bad.status().message().find("submap 7"), std::string::npos) << bad.status().ToString();
  Eigen::Isometry3d nan = Eigen::Isometry3d::Identity();
  nan.translation().x() = NAN;
  bad = ExtendGlobalMap("", {{3, nan, h.west}}, {});
  EXPECT_EQ(bad.status().code(), StatusCode::kInvalidArgument);
  EXPECT_NE(bad.status().message().find("submap 3"), std::string::npos);
  EXPECT_EQ(ExtendGlobalMap("", {}, {}).status().code(), StatusCode::kInvalidArgument);
  bad = ExtendGlobalMap("garbage", {{1, h.T_map_west, h.west}}, {});
  EXPECT_NE(bad.status().message().find("stored global map"), std::string::npos);
}

// A server shutting down stops a build: Unavailable, whether the map is new
// or extended, and the same inputs build as before once the flag is clear.
TEST(GlobalMapTest, AStoppedBuildEndsUnavailableWithNothing) {
  const Halves h = RoomHalves();
  std::atomic<bool> stop{true};
  auto stopped =
      ExtendGlobalMap("", {{1, h.T_map_west, h.west}, {2, h.T_map_east, h.east}}, {}, &stop);
  ASSERT_FALSE(stopped.ok());
  EXPECT_EQ(stopped.status().code(), StatusCode::kUnavailable);
  EXPECT_NE(stopped.status().message().find("stopped"), std::string::npos);
  auto first = ExtendGlobalMap("", {{1, h.T_map_west, h.west}}, {});
  ASSERT_TRUE(first.ok()) << first.status().ToString();
  EXPECT_EQ(ExtendGlobalMap(first->bt, {{2, h.T_map_east, h.east}}, {}, &stop).status().code(),
            StatusCode::kUnavailable);
  stop = false;
  auto built = ExtendGlobalMap(first->bt, {{2, h.T_map_east, h.east}}, {}, &stop);
  ASSERT_TRUE(built.ok()) << built.status().ToString();
  auto unstoppable = ExtendGlobalMap(first->bt, {{2, h.T_map_east, h.east}}, {});
  ASSERT_TRUE(unstoppable.ok());
  EXPECT_TRUE(built->bt == unstoppable->bt);
}

}  // namespace
}  // namespace mapd::voxel
