// Internal to corner matching: a rotation-invariant description of the
// direction from one corner to another, relative to the first corner's planes.
#ifndef MAPD_VOXEL_CORNER_DIRECTIONS_H_
#define MAPD_VOXEL_CORNER_DIRECTIONS_H_

#include <Eigen/Core>
#include <algorithm>
#include <cmath>

#include "voxel/corner.h"

namespace mapd::voxel::internal {

// |cos| of the angles between the unit direction `dir` and the three normals,
// ascending. Invariant to rotating the map, to the order and the signs of the
// normals.
inline Eigen::Vector3d DirectionFeature(const Corner& corner, const Eigen::Vector3d& dir) {
  double c[3];
  for (int k = 0; k < 3; ++k) c[k] = std::abs(dir.dot(corner.normals[k]));
  std::sort(c, c + 3);
  return {c[0], c[1], c[2]};
}

// Each |cos| moves by at most the angle it is rotated by (1-Lipschitz, and
// sorting keeps that in the max norm). The direction's own error is about
// 2 D / length for positions good to D / 2 each.
inline double DirectionTolerance(double normal_tolerance_rad, double consistency_distance_m,
                                 double length_m) {
  return normal_tolerance_rad + 2.0 * consistency_distance_m / std::max(length_m, 1e-12);
}

inline bool DirectionsAgree(const Eigen::Vector3d& fa, const Eigen::Vector3d& fb, double tol) {
  return (fa - fb).cwiseAbs().maxCoeff() <= tol;
}

}  // namespace mapd::voxel::internal

#endif  // MAPD_VOXEL_CORNER_DIRECTIONS_H_
