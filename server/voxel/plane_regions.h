// Internal to corner extraction (docs/algorithms.md B.2): planar regions of the
// occupied voxels by region growing on the voxel grid, one least-squares
// plane per region.
//
// Like PCL's RegionGrowing (seeds by increasing curvature; a neighbour joins
// when its normal is within the smoothness angle of the voxel it is reached
// from; only flat voxels grow further) with two changes for thick, noisy real
// walls: a neighbour must also be within region_angle_deg and within
// max_plane_distance of the region's current plane (refitted as the region
// doubles), so that a region cannot creep round a rounded edge, and the
// neighbourhood is the voxel grid's own (26 neighbours), not a k-d tree.
#ifndef MAPD_VOXEL_PLANE_REGIONS_H_
#define MAPD_VOXEL_PLANE_REGIONS_H_

#include <Eigen/Core>
#include <cmath>
#include <vector>

#include "voxel/corner_voxel_index.h"
#include "voxel/normals_grid.h"
#include "voxel/voxel_grid.h"

namespace mapd::voxel::internal {

// n . p + offset = 0 with |n| = 1, p in voxel units (key + 0.5).
struct FittedPlane {
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();
  double offset = 0.0;
  double rms = 0.0;  // voxels
  int size = 0;      // voxels in the region
  double Distance(const Eigen::Vector3d& p) const { return std::abs(normal.dot(p) + offset); }
};

struct PlaneRegionParams {
  double smoothness_deg = 15.0;    // neighbour to the voxel it is reached from
  double region_angle_deg = 15.0;  // neighbour to the region's running plane
  double curvature_threshold = 0.05;
  double max_plane_distance = 1.5;  // voxels, from the region's running plane
  int min_region_size = 30;
  double max_plane_rms = 0.6;  // voxels
};

struct PlaneRegions {
  std::vector<FittedPlane> planes;
  std::vector<int> label;  // per voxel: index into planes, -1 when in none
};

PlaneRegions GrowPlaneRegions(const std::vector<VoxelKey>& keys, const VoxelIndex& index,
                              const GridNormals& normals, const PlaneRegionParams& params);

// Least-squares plane of points (voxel units); rms = root mean square distance.
FittedPlane FitPlane(const std::vector<Eigen::Vector3d>& points);

}  // namespace mapd::voxel::internal

#endif  // MAPD_VOXEL_PLANE_REGIONS_H_
