#include "voxel/lattice_pose.h"

#include <algorithm>
#include <array>
#include <cmath>

namespace mapd::voxel {

std::optional<Eigen::Matrix3d> NearestLatticeRotation(const Eigen::Matrix3d& R,
                                                      double max_angle_rad) {
  if (!R.allFinite() || !(max_angle_rad >= 0)) return std::nullopt;
  // The 48 signed permutations; the 24 with det +1 are rotations. The angle
  // between R and S is acos((trace(S^T R) - 1) / 2): the nearest S has the
  // largest trace(S^T R).
  static constexpr std::array<std::array<int, 3>, 6> kPermutations = {
      {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}}};
  std::optional<Eigen::Matrix3d> best;
  double best_trace = -4.0;
  for (const auto& perm : kPermutations) {
    for (int signs = 0; signs < 8; ++signs) {
      Eigen::Matrix3d S = Eigen::Matrix3d::Zero();
      for (int row = 0; row < 3; ++row) S(row, perm[row]) = (signs >> row & 1) ? -1.0 : 1.0;
      if (S.determinant() < 0) continue;
      const double trace = (S.transpose() * R).trace();
      if (trace > best_trace) {
        best_trace = trace;
        best = S;
      }
    }
  }
  const double angle = std::acos(std::clamp((best_trace - 1.0) / 2.0, -1.0, 1.0));
  if (angle > max_angle_rad) return std::nullopt;
  return best;
}

std::vector<Eigen::Isometry3d> LatticePosesNear(const Eigen::Isometry3d& T,
                                                const Eigen::Vector3d& pivot, double voxel_m,
                                                double max_angle_rad) {
  std::vector<Eigen::Isometry3d> poses;
  if (!T.matrix().allFinite() || !pivot.allFinite() || !(voxel_m > 0) || !std::isfinite(voxel_m))
    return poses;
  const std::optional<Eigen::Matrix3d> S = NearestLatticeRotation(T.linear(), max_angle_rad);
  if (!S) return poses;
  // S p + t = T p at the pivot.
  Eigen::Vector3d t_voxels = (T * pivot - *S * pivot) / voxel_m;
  // Within rounding of a whole voxel is that voxel (one choice, not two).
  for (int axis = 0; axis < 3; ++axis) {
    const double whole = std::round(t_voxels[axis]);
    if (std::abs(t_voxels[axis] - whole) < 1e-6) t_voxels[axis] = whole;
  }
  const Eigen::Vector3d low = t_voxels.array().floor();
  for (int corner = 0; corner < 8; ++corner) {
    Eigen::Vector3d t = low;
    bool distinct = true;  // a whole number on an axis has one choice there
    for (int axis = 0; axis < 3; ++axis) {
      if ((corner >> axis & 1) == 0) continue;
      distinct = distinct && t_voxels[axis] != low[axis];
      t[axis] += 1.0;
    }
    if (!distinct) continue;
    Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
    pose.linear() = *S;
    pose.translation() = t * voxel_m;
    poses.push_back(pose);
  }
  return poses;
}

}  // namespace mapd::voxel
