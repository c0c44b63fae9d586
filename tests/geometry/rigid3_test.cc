// Rigid3: rotation then translation, inverse, composition of frames.
#include "geometry/rigid3.h"

#include <gtest/gtest.h>

#include <cmath>

namespace mapd::geometry {
namespace {

Rigid3 YawAndShift(double yaw_rad, const Eigen::Vector3d& t) {
  return {Eigen::Quaterniond(Eigen::AngleAxisd(yaw_rad, Eigen::Vector3d::UnitZ())), t};
}

TEST(Rigid3Test, AppliesRotationThenTranslation) {
  const Rigid3 T_map_sensor = YawAndShift(M_PI / 2, {1, 2, 3});
  const Eigen::Vector3d p = T_map_sensor * Eigen::Vector3d(1, 0, 0);
  EXPECT_NEAR((p - Eigen::Vector3d(1, 3, 3)).norm(), 0.0, 1e-12);
}

TEST(Rigid3Test, InverseUndoesTheTransform) {
  const Rigid3 T = YawAndShift(0.7, {-4, 5, 0.5});
  const Eigen::Vector3d p(0.3, -2, 7);
  EXPECT_NEAR(((T.inverse() * (T * p)) - p).norm(), 0.0, 1e-12);
  EXPECT_NEAR(((T * T.inverse()) * p - p).norm(), 0.0, 1e-12);
}

TEST(Rigid3Test, ComposesLikeFrames) {
  const Rigid3 T_a_b = YawAndShift(0.3, {1, 0, 0});
  const Rigid3 T_b_c = YawAndShift(-1.1, {0, 2, 1});
  const Eigen::Vector3d p_c(1, 1, 1);
  EXPECT_NEAR(((T_a_b * T_b_c) * p_c - T_a_b * (T_b_c * p_c)).norm(), 0.0, 1e-12);
}

}  // namespace
}  // namespace mapd::geometry
