// Organised 3D scans to planes: a floor and a wall in the sensor frame with
// their normals towards the sensor, a wall across the columns' seam whole only
// when the columns wrap, no returns, and bad input named.
#include "client/robot/cloud_planes.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>

namespace mapd::robot {
namespace {

// A 16-beam spinning LiDAR 1 m above a floor (z = -1) facing a wall x = 4
// (|y| <= 3, up to z = 2); azimuth of column c: first_azimuth + c deg.
OrganisedCloud Room(double first_azimuth_deg, bool wrap) {
  OrganisedCloud cloud;
  cloud.rows = 16;
  cloud.columns = 360;
  cloud.wrap_columns = wrap;
  const float nan = std::numeric_limits<float>::quiet_NaN();
  for (int r = 0; r < cloud.rows; ++r) {
    const double elevation = (-15.0 + 2.0 * r) * M_PI / 180;
    for (int c = 0; c < cloud.columns; ++c) {
      const double azimuth = (first_azimuth_deg + c) * M_PI / 180;
      const Eigen::Vector3d d(std::cos(elevation) * std::cos(azimuth),
                              std::cos(elevation) * std::sin(azimuth), std::sin(elevation));
      double t = 30;
      if (d.z() < 0) t = std::min(t, -1.0 / d.z());
      if (d.x() > 0) {
        const double hit = 4.0 / d.x();
        const Eigen::Vector3d p = hit * d;
        if (std::abs(p.y()) <= 3 && p.z() <= 2 && hit < t) t = hit;
      }
      const Eigen::Vector3f hit = (t * d).cast<float>();
      cloud.points.push_back(t < 30 ? hit : Eigen::Vector3f::Constant(nan));
    }
  }
  return cloud;
}

int CountNear(const std::vector<ExtractedPlane>& planes, const Eigen::Vector3d& normal,
              double offset) {
  int n = 0;
  for (const ExtractedPlane& p : planes) {
    if (p.feature.normal.dot(normal) > std::cos(M_PI / 180) &&
        std::abs(p.feature.offset - offset) < 0.02) {
      ++n;
      EXPECT_GE(p.feature.boundary.size(), 3U);
      EXPECT_LT(p.rms_m, 0.01);  // the floor takes the wall's foot within 6 cm
    }
  }
  return n;
}

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
  params = PlaneExtractionParams();
  params.distance_m = std::nan("");
  EXPECT_NE(params.Validate().message().find("distance_m"), std::string::npos);
}

}  // namespace
}  // namespace mapd::robot
