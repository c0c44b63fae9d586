// The client's rigid transform: application order, quaternion normalisation,
// and the identity for a zero or non-finite quaternion.
#include "client/rigid_transform.h"

#include <gtest/gtest.h>

#include <cmath>

namespace mapd::client {
namespace {

TEST(RigidTransformTest, AQuarterTurnAboutZMovesXOntoYAndReadsAsYaw90) {
  const double h = std::sqrt(0.5);
  const RigidTransform T = RigidTransform::FromQuaternion(h, 0, 0, h, {1, 2, 3});
  const Point3 p = T.Apply({1, 0, 0});
  EXPECT_NEAR(p.x, 1, 1e-12);
  EXPECT_NEAR(p.y, 3, 1e-12);
  EXPECT_NEAR(p.z, 3, 1e-12);
  double yaw, pitch, roll;
  T.YawPitchRollDeg(&yaw, &pitch, &roll);
  EXPECT_NEAR(yaw, 90, 1e-9);
  EXPECT_NEAR(pitch, 0, 1e-9);
  EXPECT_NEAR(roll, 0, 1e-9);
}

TEST(RigidTransformTest, AnUnnormalisedQuaternionIsNormalised) {
  const RigidTransform T = RigidTransform::FromQuaternion(0, 2, 0, 0, {});  // 180 deg about x
  const Point3 p = T.Apply({0, 1, 0});
  EXPECT_NEAR(p.y, -1, 1e-12);
  double yaw, pitch, roll;
  T.YawPitchRollDeg(&yaw, &pitch, &roll);
  EXPECT_NEAR(std::abs(roll), 180, 1e-9);
}

TEST(RigidTransformTest, AZeroOrNonFiniteQuaternionGivesTheIdentityRotation) {
  for (const double bad : {0.0, std::nan("")}) {
    const RigidTransform T = RigidTransform::FromQuaternion(bad, bad, bad, bad, {0, 0, 1});
    const Point3 p = T.Apply({4, 5, 6});
    EXPECT_EQ(p.x, 4);
    EXPECT_EQ(p.y, 5);
    EXPECT_EQ(p.z, 7);
  }
}

}  // namespace
}  // namespace mapd::client
