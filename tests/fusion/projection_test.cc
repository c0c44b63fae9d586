// Projection of line and plane observations to ground-plane segments
// (yaw, translation, height ranges, tilted planes kept apart, bad input refused).
#include "fusion/projection.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

namespace mapd::fusion {
namespace {

using geometry::LineFeature3;
using geometry::PlaneFeature;
using geometry::Rigid3;
using geometry::SensorObservation;
using geometry::Vec2;

Rigid3 Yaw(double yaw_rad, const Eigen::Vector3d& t) {
  return {Eigen::Quaterniond(Eigen::AngleAxisd(yaw_rad, Eigen::Vector3d::UnitZ())), t};
}

void ExpectNear(const Vec2& actual, const Vec2& expected) {
  EXPECT_NEAR((actual - expected).norm(), 0.0, 1e-12) << actual.transpose();
}

TEST(ProjectToGroundTest, LineUnderYawAndTranslation) {
  SensorObservation obs;
  obs.T_frame_sensor = Yaw(M_PI / 2, Eigen::Vector3d::Zero());
  obs.lines.push_back({{1, 0, 0}, {3, 0, 1}});
  // T_map_sensor = T_map_frame * T_frame_sensor: rotate by 90 deg, then shift.
  const auto out = ProjectToGround(obs, Yaw(0.0, {1, 2, 0.5}), 7, FusionParams());
  ASSERT_TRUE(out.ok()) << out.status().ToString();
  ASSERT_EQ(out->ground.size(), 1u);
  const GroundFeature& g = out->ground[0];
  EXPECT_EQ(g.id, 7u);
  EXPECT_EQ(g.origin, FeatureOrigin::kLine);
  ExpectNear(g.segment.a, {1, 3});
  ExpectNear(g.segment.b, {1, 5});
  EXPECT_NEAR(g.z_min_m, 0.5, 1e-12);
  EXPECT_NEAR(g.z_max_m, 1.5, 1e-12);
}

TEST(ProjectToGroundTest, VerticalPlaneBecomesASegmentWithHeightRange) {
  SensorObservation obs;
  PlaneFeature wall;  // the plane x = 2 in the sensor frame
  wall.normal = {1, 0, 0};
  wall.offset = -2.0;
  wall.boundary = {{2, 0, 0}, {2, 3, 0}, {2, 3, 2.5}, {2, 0, 2.5}, {2, 1, 1}};
  obs.planes.push_back(wall);
  const auto out = ProjectToGround(obs, Yaw(0.0, {10, 0, 1}), 1, FusionParams());
  ASSERT_TRUE(out.ok());
  ASSERT_EQ(out->ground.size(), 1u);
  const GroundFeature& g = out->ground[0];
  EXPECT_EQ(g.origin, FeatureOrigin::kPlane);
  // The plane is x = 12 in the map; the boundary spans y in [0, 3].
  const geometry::Segment2 s = g.segment;
  EXPECT_NEAR(s.a.x(), 12.0, 1e-12);
  EXPECT_NEAR(s.b.x(), 12.0, 1e-12);
  EXPECT_NEAR(std::min(s.a.y(), s.b.y()), 0.0, 1e-12);
  EXPECT_NEAR(std::max(s.a.y(), s.b.y()), 3.0, 1e-12);
  EXPECT_NEAR(g.z_min_m, 1.0, 1e-12);
  EXPECT_NEAR(g.z_max_m, 3.5, 1e-12);
  EXPECT_TRUE(out->other_planes.empty());
}

TEST(ProjectToGroundTest, RotatedVerticalPlaneKeepsItsTrace) {
  SensorObservation obs;
  PlaneFeature wall;  // x = 2 in the sensor frame, seen from a sensor yawed by 90 deg
  wall.normal = {1, 0, 0};
  wall.offset = -2.0;
  wall.boundary = {{2, -1, 0}, {2, 4, 0}, {2, 4, 2}};
  obs.planes.push_back(wall);
  const auto out = ProjectToGround(obs, Yaw(M_PI / 2, {0, 0, 0}), 1, FusionParams());
  ASSERT_TRUE(out.ok());
  ASSERT_EQ(out->ground.size(), 1u);
  // Map frame: (x, y) -> (-y, x), so the wall is y = 2 with x in [-4, 1].
  const geometry::Segment2 s = out->ground[0].segment;
  EXPECT_NEAR(s.a.y(), 2.0, 1e-12);
  EXPECT_NEAR(s.b.y(), 2.0, 1e-12);
  EXPECT_NEAR(std::min(s.a.x(), s.b.x()), -4.0, 1e-12);
  EXPECT_NEAR(std::max(s.a.x(), s.b.x()), 1.0, 1e-12);
}

TEST(ProjectToGroundTest, TiltedPlaneIsKeptApart) {
  SensorObservation obs;
  PlaneFeature ramp;
  ramp.normal = {0, std::sin(0.5), std::cos(0.5)};  // 0.5 rad from vertical normal: a ramp
  ramp.offset = 0.0;
  ramp.boundary = {{0, 0, 0}, {1, 0, 0}, {0, 1, -std::tan(0.5)}};
  obs.planes.push_back(ramp);
  const auto out = ProjectToGround(obs, Yaw(0.0, {0, 0, 2}), 40, FusionParams());
  ASSERT_TRUE(out.ok());
  EXPECT_TRUE(out->ground.empty());
  ASSERT_EQ(out->other_planes.size(), 1u);
  const MapPlane& p = out->other_planes[0];
  EXPECT_EQ(p.id, 40u);
  EXPECT_NEAR(p.offset_m, -2.0 * std::cos(0.5), 1e-12);  // d' = d - n'.t
  for (const Eigen::Vector3d& b : p.boundary) EXPECT_NEAR(p.normal.dot(b) + p.offset_m, 0.0, 1e-12);
}

TEST(ProjectToGroundTest, VerticalLineIsSkippedButConsumesItsId) {
  SensorObservation obs;
  obs.lines.push_back({{1, 1, 0}, {1, 1, 2}});  // projects to a point
  obs.lines.push_back({{0, 0, 0}, {1, 0, 0}});
  const auto out = ProjectToGround(obs, Rigid3::Identity(), 100, FusionParams());
  ASSERT_TRUE(out.ok());
  EXPECT_EQ(out->skipped, 1u);
  ASSERT_EQ(out->ground.size(), 1u);
  EXPECT_EQ(out->ground[0].id, 101u);
}

TEST(ProjectToGroundTest, NonFiniteInputIsRefusedByName) {
  SensorObservation obs;
  obs.lines.push_back({{0, 0, 0}, {1, 0, 0}});
  obs.lines.push_back({{0, 0, 0}, {std::numeric_limits<double>::quiet_NaN(), 0, 0}});
  const auto out = ProjectToGround(obs, Rigid3::Identity(), 0, FusionParams());
  EXPECT_EQ(out.status().code(), StatusCode::kInvalidArgument);
  EXPECT_THAT(out.status().message(), ::testing::HasSubstr("lines[1]"));
}

}  // namespace
}  // namespace mapd::fusion
