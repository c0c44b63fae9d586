// The closed-form rigid fit of point pairs: transform and inverse, residual
// under noise, degenerate input refused.
#include "voxel/rigid_fit.h"

#include <gtest/gtest.h>

#include <random>

namespace mapd::voxel {
namespace {

Eigen::Isometry3d RandomTransform(std::mt19937& rng) {
  std::normal_distribution<double> g(0.0, 1.0);
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::Quaterniond(g(rng), g(rng), g(rng), g(rng)).normalized().toRotationMatrix();
  T.translation() = 10.0 * Eigen::Vector3d(g(rng), g(rng), g(rng));
  return T;
}

double TransformDistance(const Eigen::Isometry3d& x, const Eigen::Isometry3d& y) {
  return (x.matrix() - y.matrix()).norm();
}

TEST(RigidFitTest, RecoversTransformAndItsInverse) {
  std::mt19937 rng(42);
  std::uniform_real_distribution<double> u(-15.0, 15.0);
  for (int rep = 0; rep < 20; ++rep) {
    const Eigen::Isometry3d T_a_b = RandomTransform(rng);
    std::vector<Eigen::Vector3d> a, b;
    for (int i = 0; i < 3 + rep; ++i) {
      b.emplace_back(u(rng), u(rng), u(rng));
      a.push_back(T_a_b * b.back());
    }
    const StatusOr<RigidFit> ab = FitRigidTransform(a, b);
    ASSERT_TRUE(ab.ok()) << ab.status().ToString();
    EXPECT_LT(TransformDistance(ab->T_target_source, T_a_b), 1e-9);
    EXPECT_LT(ab->rms_residual_m, 1e-9);
    EXPECT_EQ(ab->num_points, 3 + rep);
    const StatusOr<RigidFit> ba = FitRigidTransform(b, a);
    ASSERT_TRUE(ba.ok());
    EXPECT_LT(TransformDistance(ba->T_target_source, T_a_b.inverse()), 1e-9);
    EXPECT_NEAR(ba->T_target_source.linear().determinant(), 1.0, 1e-12);
  }
}

TEST(RigidFitTest, ResidualReflectsNoise) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-15.0, 15.0);
  std::normal_distribution<double> noise(0.0, 0.01);
  const Eigen::Isometry3d T_a_b = RandomTransform(rng);
  std::vector<Eigen::Vector3d> a, b;
  for (int i = 0; i < 2000; ++i) {
    b.emplace_back(u(rng), u(rng), u(rng));
    a.push_back(T_a_b * b.back() + Eigen::Vector3d(noise(rng), noise(rng), noise(rng)));
  }
  const StatusOr<RigidFit> fit = FitRigidTransform(a, b);
  ASSERT_TRUE(fit.ok());
  EXPECT_NEAR(fit->rms_residual_m, 0.01 * std::sqrt(3.0), 0.001);
  EXPECT_GE(fit->max_residual_m, fit->rms_residual_m);
  EXPECT_LT(TransformDistance(fit->T_target_source, T_a_b), 1e-3);
}

TEST(RigidFitTest, RejectsDegenerateInput) {
  const std::vector<Eigen::Vector3d> line = {{0, 0, 0}, {1, 1, 1}, {2, 2, 2}, {3, 3, 3}};
  EXPECT_EQ(FitRigidTransform(line, line).status().code(), StatusCode::kInvalidArgument);
  const std::vector<Eigen::Vector3d> two = {{0, 0, 0}, {1, 0, 0}};
  EXPECT_FALSE(FitRigidTransform(two, two).ok());
  const std::vector<Eigen::Vector3d> tri = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  EXPECT_FALSE(FitRigidTransform(tri, two).ok());
  std::vector<Eigen::Vector3d> nan = tri;
  nan[1].x() = std::nan("");
  EXPECT_FALSE(FitRigidTransform(tri, nan).ok());
  EXPECT_TRUE(FitRigidTransform(tri, tri).ok());  // three non-collinear points suffice
}

}  // namespace
}  // namespace mapd::voxel
