// Generated corner sets with ground truth for corner-matching tests and the
// bench: A has num_a corners in a box; B sees `overlap` of them, moved by a
// random rigid transform with position and normal noise, plus random outlier
// corners that make up `outlier_fraction` of B.
#ifndef MAPD_TESTS_VOXEL_SUPPORT_CORNER_SCENE_H_
#define MAPD_TESTS_VOXEL_SUPPORT_CORNER_SCENE_H_

#include <Eigen/Geometry>
#include <cstdint>
#include <vector>

#include "voxel/corner.h"
#include "voxel/corner_matching.h"

namespace mapd::testing {

struct CornerSceneOptions {
  int num_a = 60;
  double box_m = 30.0;                           // corners uniform in [0, box]^3
  double overlap = 0.5;                          // fraction of A's corners also in B
  double outlier_fraction = 0.5;                 // fraction of B's corners that are not in A
  double noise_m = 0.015;                        // position noise (std dev per axis) in B
  double normal_noise_rad = 1.0 * M_PI / 180.0;  // tilt of B's normals
  double manhattan_fraction = 0.5;               // corners with three orthogonal planes
  uint32_t seed = 1;
};

struct CornerScene {
  voxel::CornerSet a, b;
  Eigen::Isometry3d T_a_b = Eigen::Isometry3d::Identity();  // maps B into A
  std::vector<voxel::CornerPair> truth;                     // sorted by a
};

CornerScene MakeCornerScene(const CornerSceneOptions& options);

// Angle of R_est^T R_ref in degrees and the translation difference in metres.
double RotationErrorDeg(const Eigen::Isometry3d& est, const Eigen::Isometry3d& ref);
double TranslationError(const Eigen::Isometry3d& est, const Eigen::Isometry3d& ref);

}  // namespace mapd::testing

#endif  // MAPD_TESTS_VOXEL_SUPPORT_CORNER_SCENE_H_
