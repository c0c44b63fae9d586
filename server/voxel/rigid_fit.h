// Least-squares rigid transform between matched points (docs/algorithms.md B.5, Eq. 30):
// Umeyama's closed form without scaling (Kabsch), via Eigen::umeyama.
// "Least-squares estimation of transformation parameters between two point
// patterns", Umeyama 1991, eq. (39)-(42) with c = 1.
#ifndef MAPD_VOXEL_RIGID_FIT_H_
#define MAPD_VOXEL_RIGID_FIT_H_

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <vector>

#include "common/status.h"

namespace mapd::voxel {

struct RigidFit {
  // Minimises sum |target[i] - T_target_source * source[i]|^2 over rotations
  // and translations.
  Eigen::Isometry3d T_target_source = Eigen::Isometry3d::Identity();
  double rms_residual_m = 0.0;  // sqrt(mean |target[i] - T * source[i]|^2)
  double max_residual_m = 0.0;
  int num_points = 0;
};

// T_target_source from pairs target[i] <-> source[i]. InvalidArgument when
// the sizes differ, there are fewer than 3 pairs, a value is not finite, or
// the source points are (nearly) collinear, where the rotation about their
// line is not determined: the second largest standard deviation of the source
// points along a principal axis must exceed `min_spread_m`.
StatusOr<RigidFit> FitRigidTransform(const std::vector<Eigen::Vector3d>& target,
                                     const std::vector<Eigen::Vector3d>& source,
                                     double min_spread_m = 1e-6);

// The residuals of an existing transform on the same pairs.
// REQUIRES: target.size() == source.size().
void ComputeResiduals(const std::vector<Eigen::Vector3d>& target,
                      const std::vector<Eigen::Vector3d>& source,
                      const Eigen::Isometry3d& T_target_source, RigidFit* fit);

}  // namespace mapd::voxel

#endif  // MAPD_VOXEL_RIGID_FIT_H_
