// The baseline a user would try instead of corner matching: PCL's global
// registration on the occupied voxel centres, as in PCL's tutorial "Robust pose
// estimation of rigid objects" (VoxelGrid downsample, NormalEstimationOMP,
// FPFHEstimationOMP, SampleConsensusPrerejective), then IterativeClosestPoint.
// The tutorial's metric parameters (leaf 5 mm, normals 1 cm, features 2.5 cm,
// inlier distance 2.5 leaves) are scaled by the map's voxel size through the
// leaf: leaf = leaf_voxels * resolution, the radii in leaves.
//
// SampleConsensusPrerejective draws its samples with std::rand(); AlignFpfh
// seeds it with std::srand(params.seed), so a run is deterministic (and not
// reentrant: call it from one thread at a time).
#ifndef MAPD_TESTS_BENCH_FPFH_BASELINE_H_
#define MAPD_TESTS_BENCH_FPFH_BASELINE_H_

#include <Eigen/Geometry>
#include <cstddef>
#include <vector>

#include "common/status.h"

namespace mapd::bench {

struct FpfhParams {
  // VoxelGrid leaf, in map voxels: 3 leaves 15-30k points per 150k-voxel crop
  // (2 gives 30-60k and doubles the time of features and RANSAC).
  double leaf_voxels = 3.0;
  double normal_radius_leaves = 2.0;       // tutorial: 0.01 m / 0.005 m
  double feature_radius_leaves = 5.0;      // tutorial: 0.025 m / 0.005 m
  int max_iterations = 50000;              // tutorial
  int num_samples = 3;                     // tutorial
  int correspondence_randomness = 5;       // tutorial
  double similarity_threshold = 0.9;       // tutorial: polygonal edge-length ratio
  double max_correspondence_leaves = 2.5;  // tutorial: 2.5 * leaf
  double inlier_fraction = 0.25;           // tutorial: accept with >= 25 % inliers
  // ICP from the RANSAC pose, on the downsampled clouds (or on every voxel
  // centre: ~0.3 s per iteration at 120k points on this machine).
  bool icp_full_resolution = false;
  double icp_max_correspondence_voxels = 4.0;
  int icp_max_iterations = 30;
  int threads = 1;  // OpenMP threads for normals and features
  unsigned seed = 1;

  Status Validate() const;
};

struct FpfhTimes {
  double downsample_s = 0, normals_s = 0, features_s = 0, ransac_s = 0, icp_s = 0;
  double Total() const { return downsample_s + normals_s + features_s + ransac_s + icp_s; }
};

struct FpfhResult {
  // False when SampleConsensusPrerejective found no pose with the required
  // inlier fraction: the baseline's "refusal".
  bool accepted = false;
  Eigen::Isometry3d T_a_b = Eigen::Isometry3d::Identity();  // maps B into A's frame
  double ransac_inlier_fraction = 0.0;
  double icp_fitness_m2 = 0.0;             // PCL's fitness score: mean squared distance, m^2
  std::size_t points_a = 0, points_b = 0;  // after downsampling
  FpfhTimes times;
};

// Aligns cloud B (source) to cloud A (target); points in metres, resolution =
// the map's voxel edge (metres). InvalidArgument for bad params, an empty cloud
// or a resolution that is not finite and > 0.
StatusOr<FpfhResult> AlignFpfh(const std::vector<Eigen::Vector3d>& a,
                               const std::vector<Eigen::Vector3d>& b, double resolution,
                               const FpfhParams& params);

}  // namespace mapd::bench

#endif  // MAPD_TESTS_BENCH_FPFH_BASELINE_H_
