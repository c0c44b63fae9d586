// Internal to corner extraction (docs/algorithms.md B.2-B.3): do three planes
// really meet at their intersection point? The paper accepts a candidate that
// lies within epsilon of three planes; three infinite planes can cross where
// none of them has a voxel (a wall, the floor and a far shelf side). Here each
// plane must have its own occupied voxels near the intersection, and the
// corner is then refined from those local faces only (least squares per face,
// then the least-squares intersection), so that a long, slightly bent wall
// does not move the corner.
#ifndef MAPD_VOXEL_CORNER_FACES_H_
#define MAPD_VOXEL_CORNER_FACES_H_

#include <Eigen/Core>
#include <array>
#include <vector>

#include "voxel/corner_voxel_index.h"
#include "voxel/plane_regions.h"
#include "voxel/voxel_grid.h"

namespace mapd::voxel::internal {

struct FaceParams {
  double support_radius = 6.0;  // voxels around the corner that count as "near"
  // A voxel belongs to face k when within band of plane k and further than
  // band from the two others (voxels on an edge belong to neither).
  double band = 1.0;
  int min_support = 8;                // voxels per face
  double min_determinant = 0.1;       // |det| of the three unit normals
  int refine_iterations = 2;          // local refits; 0 keeps the global planes
  double max_refine_tilt_deg = 15.0;  // a local refit further off is not used
};

struct MeetingFaces {
  Eigen::Vector3d position;                  // voxel units (key + 0.5 = centre)
  std::array<FittedPlane, 3> planes;         // local planes (or the global ones)
  std::array<Eigen::Vector3d, 3> face_mean;  // mean of each face's voxels near the corner
  std::array<int, 3> support{};              // voxels per face near the corner
};

// Intersection of `planes`; nullopt-like false when the normals are too close
// to dependent. Voxel units.
bool IntersectPlanes(const std::array<FittedPlane, 3>& planes, double min_determinant,
                     Eigen::Vector3d* point);

// True when the three planes meet at a point where each has min_support
// voxels of its own; fills `faces`.
bool FacesMeet(const std::vector<VoxelKey>& keys, const VoxelIndex& index,
               const std::array<FittedPlane, 3>& planes, const FaceParams& params,
               MeetingFaces* faces);

}  // namespace mapd::voxel::internal

#endif  // MAPD_VOXEL_CORNER_FACES_H_
