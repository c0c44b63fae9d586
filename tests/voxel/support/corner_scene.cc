#include "voxel/support/corner_scene.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <random>

namespace mapd::testing {
namespace {

using Rng = std::mt19937;

Eigen::Quaterniond RandomRotation(Rng& rng) {
  std::normal_distribution<double> g(0.0, 1.0);
  Eigen::Quaterniond q(g(rng), g(rng), g(rng), g(rng));
  return q.normalized();
}

Eigen::Vector3d RandomUnit(Rng& rng) {
  std::normal_distribution<double> g(0.0, 1.0);
  return Eigen::Vector3d(g(rng), g(rng), g(rng)).normalized();
}

// Three plane normals: an orthogonal frame, or three directions pairwise at
// least 30 deg apart as lines (docs/algorithms.md B.2), randomly rotated.
std::array<Eigen::Vector3d, 3> RandomNormals(Rng& rng, bool manhattan) {
  if (manhattan) {
    const Eigen::Matrix3d R = RandomRotation(rng).toRotationMatrix();
    return {R.col(0), R.col(1), R.col(2)};
  }
  const double min_cos = std::cos(30.0 * M_PI / 180.0);
  while (true) {
    std::array<Eigen::Vector3d, 3> n{RandomUnit(rng), RandomUnit(rng), RandomUnit(rng)};
    if (std::abs(n[0].dot(n[1])) < min_cos && std::abs(n[0].dot(n[2])) < min_cos &&
        std::abs(n[1].dot(n[2])) < min_cos) {
      return n;
    }
  }
}

Eigen::Vector3d Tilt(const Eigen::Vector3d& n, double angle_rad, Rng& rng) {
  return Eigen::AngleAxisd(angle_rad, RandomUnit(rng)) * n;
}

}  // namespace

CornerScene MakeCornerScene(const CornerSceneOptions& o) {
  Rng rng(o.seed);
  std::uniform_real_distribution<double> in_box(0.0, o.box_m);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::normal_distribution<double> noise(0.0, o.noise_m);
  std::normal_distribution<double> tilt(0.0, o.normal_noise_rad);

  CornerScene scene;
  scene.T_a_b.linear() = RandomRotation(rng).toRotationMatrix();
  scene.T_a_b.translation() = Eigen::Vector3d(in_box(rng), in_box(rng), in_box(rng)) -
                              Eigen::Vector3d::Constant(o.box_m / 2);
  const Eigen::Isometry3d T_b_a = scene.T_a_b.inverse();

  for (int i = 0; i < o.num_a; ++i) {
    voxel::Corner c;
    c.position = {in_box(rng), in_box(rng), in_box(rng)};
    c.normals = RandomNormals(rng, unit(rng) < o.manhattan_fraction);
    c.support = 10;
    scene.a.push_back(c);
  }
  const int shared = static_cast<int>(std::lround(o.overlap * o.num_a));
  const int outliers =
      static_cast<int>(std::lround(shared * o.outlier_fraction / (1.0 - o.outlier_fraction)));
  // B's corners in a random order: shared ones first in `slots`, then shuffled.
  std::vector<int> slots(shared + outliers);
  std::iota(slots.begin(), slots.end(), 0);
  std::shuffle(slots.begin(), slots.end(), rng);
  scene.b.resize(shared + outliers);
  for (int k = 0; k < shared; ++k) {  // A's corners are already random: take the first ones
    const voxel::Corner& ca = scene.a[k];
    voxel::Corner& cb = scene.b[slots[k]];
    cb.position = T_b_a * ca.position + Eigen::Vector3d(noise(rng), noise(rng), noise(rng));
    for (int j = 0; j < 3; ++j)
      cb.normals[j] = Tilt(T_b_a.linear() * ca.normals[j], tilt(rng), rng);
    cb.support = 10;
    scene.truth.push_back({k, slots[k]});
  }
  for (int k = shared; k < shared + outliers; ++k) {
    voxel::Corner& cb = scene.b[slots[k]];
    cb.position = T_b_a * Eigen::Vector3d(in_box(rng), in_box(rng), in_box(rng));
    cb.normals = RandomNormals(rng, unit(rng) < o.manhattan_fraction);
    cb.support = 10;
  }
  return scene;
}

double RotationErrorDeg(const Eigen::Isometry3d& est, const Eigen::Isometry3d& ref) {
  const Eigen::AngleAxisd d(Eigen::Matrix3d(est.linear().transpose() * ref.linear()));
  return std::abs(d.angle()) * 180.0 / M_PI;
}

double TranslationError(const Eigen::Isometry3d& est, const Eigen::Isometry3d& ref) {
  return (est.translation() - ref.translation()).norm();
}

}  // namespace mapd::testing
