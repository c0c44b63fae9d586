// 3D scans to planes: a floor and a wall in the sensor frame with their
// normals towards the sensor, a wall across the columns' seam whole only when
// the columns wrap, the same scan unorganised and shuffled, two coplanar walls
// kept apart by the gap between them, region growing on a dense room, no
// returns, and bad input named.
#include "client/robot/cloud_planes.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <string>

#include "robot/room_scan.h"

namespace mapd::robot {
namespace {

using scenes::CountNear;
using scenes::Room;

TEST(CloudPlanesTest, TheFloorAndTheWallFacingTheSensor) {
  PlaneExtractionStats stats;
  const OrganisedCloud room = Room(-180, true);
  const auto planes = ExtractPlanes(room, PlaneExtractionParams(), &stats);
  ASSERT_TRUE(planes.ok()) << planes.status().message();
  EXPECT_EQ(CountNear(*planes, Eigen::Vector3d::UnitZ(), 1.0), 1);   // the floor, 1 m below
  EXPECT_EQ(CountNear(*planes, -Eigen::Vector3d::UnitX(), 4.0), 1);  // the wall, 4 m ahead
  EXPECT_EQ(planes->size(), 2U);
  EXPECT_GE(stats.ransac_rounds, 2U);
  for (const ExtractedPlane& p : *planes) {
    for (int i : p.indices) {  // every index a point on the plane
      const Eigen::Vector3d q = room.points[static_cast<size_t>(i)].cast<double>();
      EXPECT_NEAR(p.feature.normal.dot(q) + p.feature.offset, 0.0, 0.07);
    }
  }
}

// The wall straddles the seam between the last column and the first: one
// plane when the columns wrap (a 360 deg scan), two pieces when they do not.
TEST(CloudPlanesTest, ColumnsWrapOnlyWhenTheScanGoesAllRound) {
  const auto wrapped = ExtractPlanes(Room(0, true), PlaneExtractionParams());
  ASSERT_TRUE(wrapped.ok());
  EXPECT_EQ(CountNear(*wrapped, -Eigen::Vector3d::UnitX(), 4.0), 1);
  const auto cut = ExtractPlanes(Room(0, false), PlaneExtractionParams());
  ASSERT_TRUE(cut.ok());
  EXPECT_EQ(CountNear(*cut, -Eigen::Vector3d::UnitX(), 4.0), 2);
}

// The room densely sampled as an unorganised cloud, in a shuffled order: the
// same two planes, joined in space instead of in the image.
TEST(CloudPlanesTest, AnUnorganisedCloudHasTheSamePlanes) {
  std::vector<Eigen::Vector3f> points = scenes::DenseRoom();
  std::mt19937 random(7);
  std::shuffle(points.begin(), points.end(), random);
  PlaneExtractionStats stats;
  const auto planes = ExtractPlanes(points, PlaneExtractionParams(), &stats);
  ASSERT_TRUE(planes.ok()) << planes.status().message();
  EXPECT_EQ(CountNear(*planes, Eigen::Vector3d::UnitZ(), 1.0), 1);
  EXPECT_EQ(CountNear(*planes, -Eigen::Vector3d::UnitX(), 4.0), 1);
  EXPECT_EQ(planes->size(), 2U);
  EXPECT_EQ(stats.rejected_rows, 0U);  // no rows to count
}

// Two 2 x 2 m patches of the plane x = 5, 3 m apart along y, sampled every
// 10 cm: one RANSAC plane, two components, two observations; a gap under the
// jump limit (0.3 m + 3 % of the range) joins them.
TEST(CloudPlanesTest, CoplanarWallsApartInSpaceStayApart) {
  const auto patches = [](double gap_m) {
    std::vector<Eigen::Vector3f> points;
    for (double y = 0; y <= 2.0; y += 0.1) {
      for (double z = 0; z <= 2.0; z += 0.1) {
        points.emplace_back(5.0f, static_cast<float>(y), static_cast<float>(z));
        points.emplace_back(5.0f, static_cast<float>(2.0 + gap_m + y), static_cast<float>(z));
      }
    }
    return points;
  };
  const auto apart = ExtractPlanes(patches(3.0), PlaneExtractionParams());
  ASSERT_TRUE(apart.ok());
  EXPECT_EQ(CountNear(*apart, -Eigen::Vector3d::UnitX(), 5.0), 2);
  const auto joined = ExtractPlanes(patches(0.2), PlaneExtractionParams());
  ASSERT_TRUE(joined.ok());
  EXPECT_EQ(CountNear(*joined, -Eigen::Vector3d::UnitX(), 5.0), 1);
}

// Region growing (the measured alternative) finds the dense room's two
// planes too, through the same gates.
TEST(CloudPlanesTest, RegionGrowingFindsTheDenseRoom) {
  PlaneExtractionParams params;
  params.segmentation = PlaneSegmentation::kRegionGrowing;
  const auto planes = ExtractPlanes(scenes::DenseRoom(), params);
  ASSERT_TRUE(planes.ok()) << planes.status().message();
  EXPECT_EQ(CountNear(*planes, Eigen::Vector3d::UnitZ(), 1.0), 1);
  EXPECT_EQ(CountNear(*planes, -Eigen::Vector3d::UnitX(), 4.0), 1);
  params.smoothness_deg = 0;
  EXPECT_NE(params.Validate().message().find("smoothness_deg"), std::string::npos);
  params = PlaneExtractionParams();
  params.normal_neighbours = 2;
  EXPECT_NE(params.Validate().message().find("normal_neighbours"), std::string::npos);
  params = PlaneExtractionParams();
  params.max_curvature = 2;
  EXPECT_NE(params.Validate().message().find("max_curvature"), std::string::npos);
}

TEST(CloudPlanesTest, NoReturnsIsNoPlanesAndBadInputIsNamed) {
  OrganisedCloud empty = Room(-180, true);
  for (auto& p : empty.points) p = Eigen::Vector3f::Constant(std::nanf(""));
  const auto none = ExtractPlanes(empty, PlaneExtractionParams());
  ASSERT_TRUE(none.ok());
  EXPECT_TRUE(none->empty());

  OrganisedCloud short_cloud = Room(-180, true);
  short_cloud.points.pop_back();
  const auto refused = ExtractPlanes(short_cloud, PlaneExtractionParams());
  ASSERT_FALSE(refused.ok());
  EXPECT_EQ(refused.status().code(), StatusCode::kInvalidArgument);
  EXPECT_NE(refused.status().message().find("16 x 360, 5759 points"), std::string::npos)
      << refused.status().message();

  PlaneExtractionParams params;
  params.min_inliers = 2;
  const auto bad = ExtractPlanes(Room(-180, true), params);
  ASSERT_FALSE(bad.ok());
  EXPECT_NE(bad.status().message().find("min_inliers"), std::string::npos);
  const auto bad_unorganised = ExtractPlanes(std::vector<Eigen::Vector3f>(), params);
  EXPECT_EQ(bad_unorganised.status().code(), StatusCode::kInvalidArgument);
  const auto nothing = ExtractPlanes(std::vector<Eigen::Vector3f>(), PlaneExtractionParams());
  ASSERT_TRUE(nothing.ok());
  EXPECT_TRUE(nothing->empty());
  params = PlaneExtractionParams();
  params.distance_m = std::nan("");
  EXPECT_NE(params.Validate().message().find("distance_m"), std::string::npos);
}

}  // namespace
}  // namespace mapd::robot
