// Corner extraction from a voxel map (grid-map-fusion paper, Qiu et al.,
// section III; docs/algorithms.md B.1-B.3):
//   1. candidates: sliding-window occupied counts, O(1) per window from a 3D
//      summed-volume table; a voxel is a candidate when shifting the window by
//      one voxel in each of the 26 directions changes its count by at least
//      tau_change (a 3D Moravec test: flat walls and straight edges have a
//      shift that changes nothing);
//   2. planes: normals from the occupied neighbours on the voxel grid, region
//      growing on the grid, a least-squares plane per region; a candidate is
//      kept for a triple of planes, pairwise >= min_plane_angle_deg apart,
//      that each pass within plane_epsilon of it (paper eq. 3) and that really
//      meet: each has min_face_support voxels of its own near the
//      intersection (corner_faces.h);
//   3. clusters: one corner per plane triple at the least-squares
//      intersection of the triple's faces refitted near the corner; corners
//      closer than cluster_radius are one cluster, the best supported stays.
#ifndef MAPD_VOXEL_CORNER_EXTRACTION_H_
#define MAPD_VOXEL_CORNER_EXTRACTION_H_

#include <cstddef>

#include "common/status.h"
#include "voxel/corner.h"
#include "voxel/voxel_grid.h"

namespace mapd::voxel {
namespace internal {
struct GridSurface;
}  // namespace internal

// Lengths in voxels (multiples of the grid's resolution) unless named _m.
struct CornerExtractionParams {
  // Working scale: corners are extracted on the map coarsened by this integer
  // factor (a coarse voxel is occupied when any of its scale^3 voxels is), and
  // every length below is in coarse voxels. Measured on the real maps
  // (docs/voxel-corners.md): scale 2 is 3-4x faster but its corners repeat
  // within 2 (fine) voxels under a rigid motion about 3x less often, so 1.
  int scale = 1;
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
  // Planes are looked for among regions with a voxel within about this
  // radius of the candidate (cells of this edge around it: 1-2 radii).
  // Normals within about normal_radius of an edge bend, so region growing
  // leaves a gap there: the radius must reach across it.
  double plane_search_radius = 5.0;
  // Normals: covariance of the occupied voxels within this ball (voxels).
  double normal_radius = 2.5;
  // Region growing on the 26-neighbourhood of the grid (plane_regions.h).
  // Real 5-20 cm maps have walls 2-3 voxels thick: the surface variation of
  // a flat wall is 0.1-0.2 there, and its plane-fit RMS up to 1 voxel.
  double smoothness_deg = 20.0;            // max normal change between neighbours
  double region_angle_deg = 18.0;          // max angle of a voxel's normal to its region's plane
  double curvature_threshold = 0.25;       // seeds must be flatter than this
  double max_region_plane_distance = 2.0;  // from the region's running plane
  int min_region_size = 30;                // voxels; smaller regions are dropped
  double max_plane_rms = 1.2;              // a region's plane-fit RMS must be below this
  // Three planes really meet (corner_faces.h): each has min_face_support
  // voxels within face_band of it (and not of the two others) within
  // face_support_radius of the intersection.
  double face_support_radius = 6.0;
  double face_band = 1.0;
  int min_face_support = 10;
  // |det| of the three unit normals: pairwise >= 30 deg apart can still be
  // nearly coplanar (three walls round a pillar).
  double min_normal_determinant = 0.1;
  // Local least-squares refits of the three faces near the corner.
  int refine_iterations = 2;
  // Candidates consider at most this many of their nearest planes.
  int max_planes_per_candidate = 6;
  // B.3: corners closer than this are one cluster (voxels).
  double cluster_radius = 3.0;
  // A corner further than this from its triple's nearest candidate is dropped
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
  // By decreasing minimum face support (voxels of the weakest face near the
  // corner). Measured: not a repeatability ranking; use them all.
  CornerSet corners;
  std::size_t occupied_voxels = 0;
  std::size_t candidates = 0;           // B.1 window test passed
  std::size_t verified_candidates = 0;  // B.2 three planes that meet passed
  std::size_t triples = 0;              // plane triples some candidate lies on
  std::size_t clusters = 0;             // B.3 triples whose planes meet (before clustering)
  std::size_t planes = 0;               // fitted plane regions
  std::size_t table_blocks = 0;         // summed-volume tables built (1 = dense)
  int scale = 1;                        // working scale used (see params.scale)
  std::size_t working_voxels = 0;       // occupied voxels at that scale
  // Wall-clock seconds per stage.
  double seconds_window = 0.0;
  double seconds_normals = 0.0;  // voxel index and normals
  double seconds_planes = 0.0;   // region growing, plane fits
  double seconds_verify = 0.0;
  double seconds_cluster = 0.0;  // faces near each triple, refits, clustering
};

// REQUIRES: nothing; an empty grid gives no corners. Errors: InvalidArgument
// for bad params, ResourceExhausted beyond max_occupied_voxels or when
// max_table_bytes cannot hold even the smallest block. `surface`, when
// given, is grid's occupied voxels' index and normals (normals_grid.h); it is
// used at scale 1 when its radius is normal_radius, else computed here.
StatusOr<CornerExtractionResult> ExtractCorners(const VoxelGrid& grid,
                                                const CornerExtractionParams& params = {},
                                                const internal::GridSurface* surface = nullptr);

}  // namespace mapd::voxel

#endif  // MAPD_VOXEL_CORNER_EXTRACTION_H_
