#include "voxel/rigid_fit.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <string>

namespace mapd::voxel {

void ComputeResiduals(const std::vector<Eigen::Vector3d>& target,
                      const std::vector<Eigen::Vector3d>& source,
                      const Eigen::Isometry3d& T_target_source, RigidFit* fit) {
  double sum_sq = 0.0;
  double max_r = 0.0;
  for (size_t i = 0; i < source.size(); ++i) {
    const double r = (target[i] - T_target_source * source[i]).norm();
    sum_sq += r * r;
    max_r = std::max(max_r, r);
  }
  fit->num_points = static_cast<int>(source.size());
  fit->rms_residual_m = source.empty() ? 0.0 : std::sqrt(sum_sq / source.size());
  fit->max_residual_m = max_r;
}

StatusOr<RigidFit> FitRigidTransform(const std::vector<Eigen::Vector3d>& target,
                                     const std::vector<Eigen::Vector3d>& source,
                                     double min_spread_m) {
  if (target.size() != source.size()) {
    return Status::InvalidArgument("rigid fit: " + std::to_string(target.size()) +
                                   " target points but " + std::to_string(source.size()) +
                                   " source points");
  }
  const int n = static_cast<int>(source.size());
  if (n < 3) {
    return Status::InvalidArgument("rigid fit: needs at least 3 point pairs, got " +
                                   std::to_string(n));
  }
  Eigen::Matrix3Xd src(3, n), dst(3, n);
  for (int i = 0; i < n; ++i) {
    if (!source[i].allFinite() || !target[i].allFinite()) {
      return Status::InvalidArgument("rigid fit: point pair " + std::to_string(i) +
                                     " is not finite");
    }
    src.col(i) = source[i];
    dst.col(i) = target[i];
  }
  // Degeneracy: with collinear sources the rotation about their line is free.
  const Eigen::Vector3d mean = src.rowwise().mean();
  const Eigen::Matrix3d cov = (src.colwise() - mean) * (src.colwise() - mean).transpose() / n;
  const Eigen::Vector3d eig = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(cov).eigenvalues();
  const double second_sigma = std::sqrt(std::max(0.0, eig(1)));  // ascending order
  if (!(second_sigma > min_spread_m)) {
    return Status::InvalidArgument("rigid fit: source points are collinear (second spread " +
                                   std::to_string(second_sigma) + " m)");
  }
  RigidFit fit;
  // Umeyama 1991 without scaling; the SVD sign correction keeps det(R) = +1.
  fit.T_target_source.matrix() = Eigen::umeyama(src, dst, /*with_scaling=*/false);
  ComputeResiduals(target, source, fit.T_target_source, &fit);
  return fit;
}

}  // namespace mapd::voxel
