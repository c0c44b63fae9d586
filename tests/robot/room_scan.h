// Shared fixtures of the plane extractor's tests: a simulated LiDAR scan of a
// room, and a count of the planes found near a given one.
#ifndef MAPD_TESTS_ROBOT_ROOM_SCAN_H_
#define MAPD_TESTS_ROBOT_ROOM_SCAN_H_

#include <gtest/gtest.h>

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "client/robot/cloud_planes.h"

namespace mapd::robot::scenes {

// A 16-beam spinning LiDAR 1 m above a floor (z = -1) facing a wall x = 4
// (|y| <= 3, up to z = 2); azimuth of column c: first_azimuth + c deg.
inline OrganisedCloud Room(double first_azimuth_deg, bool wrap) {
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

// The same room's floor and wall as a dense unorganised cloud (a depth
// camera's or a filtered cloud's spacing, 10 cm), floor before wall. A
// 16-beam scan's floor rings lie farther apart than the jump limit at range:
// unorganised, they would be rings, not a floor (docs/robot-library.md).
inline std::vector<Eigen::Vector3f> DenseRoom() {
  std::vector<Eigen::Vector3f> points;
  for (int i = 5; i < 40; ++i) {
    for (int j = -30; j <= 30; ++j) points.emplace_back(0.1f * i, 0.1f * j, -1.0f);
  }
  for (int j = -30; j <= 30; ++j) {
    for (int k = -10; k <= 20; ++k) points.emplace_back(4.0f, 0.1f * j, 0.1f * k);
  }
  return points;
}

// The sign of `normal` picks the side; `offset` in metres.
inline int CountNear(const std::vector<ExtractedPlane>& planes, const Eigen::Vector3d& normal,
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

}  // namespace mapd::robot::scenes

#endif  // MAPD_TESTS_ROBOT_ROOM_SCAN_H_
