// Internal to corner extraction: surface normals of the occupied voxels from
// the covariance of their occupied neighbours in a ball, read straight off the
// voxel grid (no k-d tree, no floating point point cloud): the neighbours'
// offsets are small integers, so the moments are exact and the cost is
// O(ball volume) per voxel with a few brick look-ups.
#ifndef MAPD_VOXEL_NORMALS_GRID_H_
#define MAPD_VOXEL_NORMALS_GRID_H_

#include <Eigen/Core>
#include <vector>

#include "voxel/corner_voxel_index.h"
#include "voxel/voxel_grid.h"

namespace mapd::voxel::internal {

struct GridNormals {
  std::vector<Eigen::Vector3f> normals;  // unit, sign arbitrary
  // Surface variation lambda_0 / (lambda_0 + lambda_1 + lambda_2) of the
  // neighbourhood covariance (PCL's "curvature"): 0 on a plane, 1/3 when
  // isotropic. 1 when the ball holds fewer than 3 voxels.
  std::vector<float> curvature;
};

// For keys[i] (indexed by `index`): the plane of its occupied neighbours whose
// centres lie within radius_voxels of its centre. REQUIRES: radius_voxels >= 1.
GridNormals ComputeGridNormals(const std::vector<VoxelKey>& keys, const VoxelIndex& index,
                               double radius_voxels);

// The occupied voxels' index and their normals at one radius: what corner
// extraction (B.2) and levelling (B.9) both start from, built once per
// submap of a merge (SubmapFeatures) when their radii agree.
struct GridSurface {
  GridSurface(const std::vector<VoxelKey>& keys, double radius)
      : index(keys), normals(ComputeGridNormals(keys, index, radius)), radius_voxels(radius) {}
  VoxelIndex index;
  GridNormals normals;
  double radius_voxels;
};

}  // namespace mapd::voxel::internal

#endif  // MAPD_VOXEL_NORMALS_GRID_H_
