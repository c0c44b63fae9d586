// Rigid3: rotation then translation, inverse, composition of frames; the
// tolerant construction from the API's quaternion and the Euler angles tables
// print.
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

TEST(Rigid3Test, AQuarterTurnAboutZMovesXOntoYAndReadsAsYaw90) {
  const double h = std::sqrt(0.5);
  const Rigid3 T = Rigid3::FromQuaternion(h, 0, 0, h, Eigen::Vector3d(1, 2, 3));
  EXPECT_NEAR((T * Eigen::Vector3d(1, 0, 0) - Eigen::Vector3d(1, 3, 3)).norm(), 0.0, 1e-12);
  double yaw, pitch, roll;
  T.YawPitchRollDeg(&yaw, &pitch, &roll);
  EXPECT_NEAR(yaw, 90, 1e-9);
  EXPECT_NEAR(pitch, 0, 1e-9);
  EXPECT_NEAR(roll, 0, 1e-9);
}

TEST(Rigid3Test, AnUnnormalisedQuaternionIsNormalised) {
  const Rigid3 T = Rigid3::FromQuaternion(0, 2, 0, 0, Eigen::Vector3d::Zero());  // 180 deg about x
  EXPECT_NEAR(T.rotation.norm(), 1.0, 1e-15);
  EXPECT_NEAR((T * Eigen::Vector3d(0, 1, 0) - Eigen::Vector3d(0, -1, 0)).norm(), 0.0, 1e-12);
  double yaw, pitch, roll;
  T.YawPitchRollDeg(&yaw, &pitch, &roll);
  EXPECT_NEAR(std::abs(roll), 180, 1e-9);
}

TEST(Rigid3Test, AZeroOrNonFiniteQuaternionGivesTheIdentityRotation) {
  for (const double bad : {0.0, std::nan("")}) {
    const Rigid3 T = Rigid3::FromQuaternion(bad, bad, bad, bad, Eigen::Vector3d(0, 0, 1));
    EXPECT_EQ(T * Eigen::Vector3d(4, 5, 6), Eigen::Vector3d(4, 5, 7));
  }
}

// Z-Y-X angles back from the rotation they make (a non-unit quaternion).
TEST(Rigid3Test, YawPitchRollRoundTrip) {
  const double yaw = 30, pitch = -20, roll = 170;
  const Eigen::Quaterniond q = Eigen::AngleAxisd(yaw * M_PI / 180, Eigen::Vector3d::UnitZ()) *
                               Eigen::AngleAxisd(pitch * M_PI / 180, Eigen::Vector3d::UnitY()) *
                               Eigen::AngleAxisd(roll * M_PI / 180, Eigen::Vector3d::UnitX());
  const Rigid3 T =
      Rigid3::FromQuaternion(2 * q.w(), 2 * q.x(), 2 * q.y(), 2 * q.z(), Eigen::Vector3d(1, 2, 3));
  double out_yaw, out_pitch, out_roll;
  T.YawPitchRollDeg(&out_yaw, &out_pitch, &out_roll);
  EXPECT_NEAR(out_yaw, yaw, 1e-9);
  EXPECT_NEAR(out_pitch, pitch, 1e-9);
  EXPECT_NEAR(out_roll, roll, 1e-9);
}

}  // namespace
}  // namespace mapd::geometry
