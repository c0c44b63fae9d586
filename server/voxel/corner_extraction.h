// Corner extraction from a voxel map (grid-map-fusion-paper.txt section III,
// ALGORITHMS.md B.1-B.3):
//   1. candidates: sliding-window occupied counts, O(1) per window from a 3D
//      summed-volume table; a voxel is a candidate when shifting the window by
//      one voxel in each of the 26 directions changes its count by at least
//      tau_change (a 3D Moravec test: flat walls and straight edges have a
//      shift that changes nothing);
//   2. planes: normals + region growing on the occupied voxel centres, a
//      least-squares plane per region; a candidate is kept when three planes
//      near it, pairwise >= min_plane_angle_deg apart, each pass within
//      plane_epsilon of it (paper eq. 3);
//   3. clusters: Euclidean clustering of the kept candidates; each cluster
//      gives one corner at the least-squares intersection of its three planes.
#ifndef MAPD_VOXEL_CORNER_EXTRACTION_H_
#define MAPD_VOXEL_CORNER_EXTRACTION_H_

#include <cstddef>

#include "common/status.h"
#include "voxel/corner.h"
#include "voxel/voxel_grid.h"

namespace mapd::voxel {

// Lengths in voxels (multiples of the grid's resolution) unless named _m.
struct CornerExtractionParams {
  // B.1: the window is window_size^3 voxels (odd, paper: 7).
  int window_size = 7;
  // Minimum |N(c + s) - N(c)| over the 26 shifts s. At an ideal corner of three
  // one-voxel-thick faces with a 7^3 window the minimum is 1; on an ideal wall
  // or edge it is 0.
  int tau_change = 1;
  // B.2: distance for a candidate to lie on a plane (paper's epsilon, eq. 3).
  // Measured from the candidate's voxel cube, not its centre: a rasterised
  // face's voxels straddle the plane, and the voxel at a corner's tip is up to
  // half a voxel (per axis) from each plane even when the plane cuts it.
  double plane_epsilon = 1.0;
  // The three planes of a corner must be pairwise at least this far apart.
  double min_plane_angle_deg = 30.0;
  // Planes are looked for among regions with a point within this radius of
  // the candidate (an infinite plane far away does not make a corner).
  // Normals within about normal_radius of an edge bend, so region growing
  // leaves a gap there: the radius must reach across it.
  double plane_search_radius = 5.0;
  // Region growing (PCL NormalEstimation + RegionGrowing).
  double normal_radius = 2.5;         // normal estimation neighbourhood
  int region_neighbours = 12;         // k of the region-growing neighbourhood
  double smoothness_deg = 15.0;       // max normal change between neighbours in a region
  double curvature_threshold = 0.05;  // seeds must be flatter than this
  int min_region_size = 30;           // points; smaller regions are dropped
  double max_plane_rms = 0.6;         // a region's plane-fit RMS must be below this
  // B.3: Euclidean clustering radius for candidates.
  double cluster_radius = 2.0;
  // A corner further than this from its cluster's nearest candidate is dropped
  // (its planes do not meet where the candidates are).
  double max_corner_offset = 3.0;
  // Memory cap of one summed-volume table (4 bytes per cell). The dense
  // bounding box is used when it fits, otherwise blocks that do.
  std::size_t max_table_bytes = std::size_t{256} << 20;
  // Occupied voxels accepted (point clouds and k-d trees scale with them).
  std::size_t max_occupied_voxels = 5'000'000;

  // InvalidArgument naming the first bad field.
  Status Validate() const;
};

// The corners and what it took to find them.
struct CornerExtractionResult {
  CornerSet corners;
  std::size_t occupied_voxels = 0;
  std::size_t candidates = 0;           // B.1 window test passed
  std::size_t verified_candidates = 0;  // B.2 three planes passed
  std::size_t clusters = 0;             // B.3 clusters of verified candidates
  std::size_t planes = 0;               // fitted plane regions
  std::size_t table_blocks = 0;         // summed-volume tables built (1 = dense)
  // Wall-clock seconds per stage.
  double seconds_window = 0.0;
  double seconds_planes = 0.0;  // normals, region growing, plane fits
  double seconds_verify = 0.0;
  double seconds_cluster = 0.0;  // clustering and plane intersections
};

// REQUIRES: nothing; an empty grid gives no corners. Errors: InvalidArgument
// for bad params, ResourceExhausted beyond max_occupied_voxels or when
// max_table_bytes cannot hold even the smallest block.
StatusOr<CornerExtractionResult> ExtractCorners(const VoxelGrid& grid,
                                                const CornerExtractionParams& params = {});

}  // namespace mapd::voxel

#endif  // MAPD_VOXEL_CORNER_EXTRACTION_H_
