// The simulated LiDAR and the plane extraction on worlds whose planes are known.
#include "sim/lidar_sim.h"

#include <gtest/gtest.h>
#include <octomap/OcTree.h>

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <string>

#include "sim/city_world.h"
#include "sim/octomap_world.h"
#include "sim/plane_extraction.h"

namespace mapd::sim {
namespace {

constexpr double kRes = 0.05;

// A closed 6 x 4 x 3 m room: inner faces at x = +-3, y = +-2, z = 0 and 3,
// walls one voxel thick, everything inside known free.
octomap::OcTree BoxRoom() {
  octomap::OcTree tree(kRes);
  for (double x = -3.025; x <= 3.03; x += kRes) {
    for (double y = -2.025; y <= 2.03; y += kRes) {
      for (double z = -0.025; z <= 3.03; z += kRes) {
        const bool wall = std::abs(x) > 3.0 || std::abs(y) > 2.0 || z < 0.0 || z > 3.0;
        tree.updateNode(
            octomap::point3d(static_cast<float>(x), static_cast<float>(y), static_cast<float>(z)),
            wall);
      }
    }
  }
  return tree;
}

geometry::Rigid3 At(double x, double y, double z) {
  geometry::Rigid3 pose;
  pose.translation = {x, y, z};
  return pose;
}

TEST(LidarParamsTest, ValidateNamesTheBadField) {
  EXPECT_TRUE(LidarParams{}.Validate().ok());
  LidarParams p;
  p.beams = 1;
  EXPECT_NE(p.Validate().message().find("beams"), std::string::npos);
  p = LidarParams{};
  p.range_sigma_m = -0.1;
  EXPECT_NE(p.Validate().message().find("range_sigma_m"), std::string::npos);
  p = LidarParams{};
  p.max_range_m = 0.2;
  EXPECT_NE(p.Validate().message().find("max_range_m"), std::string::npos);
  PlaneExtractionParams e;
  EXPECT_TRUE(e.Validate().ok());
  e.min_inliers = 0;
  EXPECT_NE(e.Validate().message().find("min_inliers"), std::string::npos);
}

TEST(LidarSimTest, BoxRoomGivesItsFourWalls) {
  const octomap::OcTree tree = BoxRoom();
  const OctoMapWorld world(tree);
  const LidarSimulator lidar(LidarParams{});
  // At 1.5 m the +-15 degree beams reach neither floor nor ceiling (5.6 m away).
  const LidarScan scan = lidar.Scan(world, At(0.3, -0.2, 1.5), 0);
  ASSERT_EQ(scan.valid_count(), scan.points.size());
  const auto planes = ExtractPlanes(scan, PlaneExtractionParams{});
  ASSERT_TRUE(planes.ok()) << planes.status().message();
  ASSERT_EQ(planes->size(), 4u);
  // Sensor-frame offsets: distance from (0.3, -0.2) to each inner face.
  const struct {
    Eigen::Vector3d normal;
    double offset;
  } expected[] = {{{-1, 0, 0}, 2.7}, {{1, 0, 0}, 3.3}, {{0, -1, 0}, 2.2}, {{0, 1, 0}, 1.8}};
  for (const auto& e : expected) {
    int found = 0;
    for (const auto& p : planes.value()) {
      if (p.feature.normal.dot(e.normal) > std::cos(1.0 * M_PI / 180.0)) {
        ++found;
        EXPECT_NEAR(p.feature.offset, e.offset, 0.03) << e.normal.transpose();
        EXPECT_GE(p.feature.boundary.size(), 3u);
      }
    }
    EXPECT_EQ(found, 1) << "wall with normal " << e.normal.transpose();
  }
}

TEST(LidarSimTest, CityWallGroundAndRamp) {
  fusion::scenario::World city;
  fusion::scenario::Structure wall;
  wall.segment = {{10.0, -20.0}, {10.0, 20.0}};
  wall.building = 0;
  city.structures.push_back(wall);
  city.wall_count = 1;
  city.buildings.push_back({{10, -20}, {30, -20}, {30, 20}, {10, 20}});
  // Behind the sensor, a ramp rising 1 m over 10 m (5.7 deg) away from it.
  Ramp ramp;
  ramp.start = {-6.0, -2.0};
  ramp.end = {-16.0, -2.0};
  const CityWorld world(city, CityHeights{}, {ramp});
  const LidarSimulator lidar(LidarParams{});
  const LidarScan scan = lidar.Scan(world, At(0.0, 0.0, 1.8), 3);
  const auto planes = ExtractPlanes(scan, PlaneExtractionParams{});
  ASSERT_TRUE(planes.ok());
  ASSERT_EQ(planes->size(), 3u);
  for (const auto& p : planes.value()) {
    if (p.label == -1) {  // ground z = 0 seen from 1.8 m: n = +z, offset 1.8
      EXPECT_GT(p.feature.normal.z(), 0.999);
      EXPECT_NEAR(p.feature.offset, 1.8, 0.02);
    } else if (p.label == -10) {  // the sensor sits at the map origin, 1.8 m up
      EXPECT_GT(p.feature.normal.dot(ramp.normal()), std::cos(1.0 * M_PI / 180.0));
      EXPECT_NEAR(p.feature.offset, ramp.offset() + 1.8 * ramp.normal().z(), 0.03);
    } else {
      EXPECT_EQ(p.label, 0);
      EXPECT_LT(p.feature.normal.x(), -0.999);
      EXPECT_NEAR(p.feature.offset, 10.0, 0.02);
    }
  }
}

TEST(PlaneExtractionTest, NothingFromNothingAndMalformedScansRefused) {
  const fusion::scenario::World empty;
  const CityWorld world(empty, CityHeights{});
  // Looking up from below the ground plane: no returns at all.
  const LidarScan scan = LidarSimulator(LidarParams{}).Scan(world, At(0.0, 0.0, -1.0), 0);
  EXPECT_EQ(scan.valid_count(), 0u);
  const auto planes = ExtractPlanes(scan, PlaneExtractionParams{});
  ASSERT_TRUE(planes.ok());
  EXPECT_TRUE(planes.value().empty());
  LidarScan bad = scan;
  bad.points.pop_back();
  const auto refused = ExtractPlanes(bad, PlaneExtractionParams{});
  ASSERT_FALSE(refused.ok());
  EXPECT_NE(refused.status().message().find("beams x columns"), std::string::npos);
}

// The real maps (the shared data folder, via MAPD_SHARED_DIR); skipped without them.
TEST(LidarSimTest, RealMapScanHasPlanes) {
  const char* shared = std::getenv("MAPD_SHARED_DIR");
  const std::string path = std::string(shared != nullptr ? shared : "") + "/data/octomap/geb079.bt";
  if (shared == nullptr || !std::ifstream(path).good()) GTEST_SKIP() << "no " << path;
  octomap::OcTree tree(0.1);
  ASSERT_TRUE(tree.readBinary(path));
  PoseSamplingParams sampling;
  sampling.count = 1;
  const auto poses = SampleFreePoses(tree, sampling);
  ASSERT_EQ(poses.size(), 1u);
  const OctoMapWorld world(tree);
  const LidarScan scan = LidarSimulator(LidarParams{}).Scan(world, poses[0], 0);
  EXPECT_GT(scan.valid_count(), scan.points.size() / 4);
  const auto planes = ExtractPlanes(scan, PlaneExtractionParams{});
  ASSERT_TRUE(planes.ok());
  EXPECT_GE(planes->size(), 2u);
}

}  // namespace
}  // namespace mapd::sim
