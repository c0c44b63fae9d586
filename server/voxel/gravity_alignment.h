// The second hypothesis generator's first half (docs/algorithms.md B.9): the
// up vector of a map from its floor and ceiling planes, and the yaw between
// two levelled maps from their wall-normal histograms. Indoor maps are built
// from gravity-levelled scans and most walls are vertical and near-Manhattan,
// so three of the six degrees of freedom and a short list of yaws come from
// statistics that need no common corner at all.
//
// Thread compatible; no shared state.
#ifndef MAPD_VOXEL_GRAVITY_ALIGNMENT_H_
#define MAPD_VOXEL_GRAVITY_ALIGNMENT_H_

#include <Eigen/Geometry>
#include <vector>

#include "common/status.h"
#include "voxel/voxel_grid.h"

namespace mapd::voxel {
namespace internal {
struct GridSurface;
}  // namespace internal

struct GravityParams {
  // Planes whose normal is within this of +-z count as floor or ceiling. The
  // merge benchmark tilts maps by up to 10 deg roll and pitch; walls are 90
  // deg away, so 30 leaves margin both ways.
  double max_up_tilt_deg = 30.0;
  // After the first estimate, only planes within this of it are averaged
  // again (drops ramps and sloped ceilings that passed the wide cone).
  double refine_up_deg = 5.0;
  // Planes whose normal is within this of horizontal (after levelling) vote in
  // the wall histogram; real walls measured within 1-3 deg of vertical.
  double max_wall_tilt_deg = 10.0;
  // Rounds of re-estimating up from the floors AND the walls: the direction
  // closest to the floor and ceiling normals and perpendicular to the wall
  // normals (least squares, weighted by plane size; floors within
  // refine_up_deg and walls within max_wall_tilt_deg of the previous
  // estimate). 0: from the floors alone. On the benchmark's tilted crops of
  // fr_078_tidyup the floors alone left the two maps 2.3-5.5 deg apart after
  // levelling, and the true translation peak of 3 of 6 pairs at 10 % overlap
  // ranked below 20th for its yaw; with the walls, 0.9-2.0 deg and every true
  // peak 1st or 2nd (docs/voxel-merge.md).
  int wall_up_rounds = 2;
  // Histogram bin and Gaussian smoothing over the 180 deg of wall directions
  // (a wall normal's sign is arbitrary). Plane fits are good to ~0.3 deg; a
  // 1 deg sigma merges one wall's fits in the two maps into one peak.
  double bin_deg = 0.5;
  double smoothing_deg = 1.0;
  // Yaw peaks kept (each also with its 180 deg twin). A Manhattan building
  // has two peaks 90 deg apart of similar height; 2 keeps both.
  int yaw_peaks = 2;
  // Peaks closer than this are one.
  double min_peak_separation_deg = 10.0;
  // Plane regions: smallest region (voxels) that votes.
  int min_plane_voxels = 50;

  Status Validate() const;
};

// Levelling of one map: R_up * up = +z (a pure rotation about the origin),
// and the wall-normal histogram after levelling (bins of bin_deg over
// [0, 180) deg, weighted by plane size, smoothed).
struct GravityFrame {
  Eigen::Vector3d up = Eigen::Vector3d::UnitZ();
  Eigen::Matrix3d R_up = Eigen::Matrix3d::Identity();
  std::vector<double> wall_histogram;
  int floor_planes = 0;  // planes that voted for up
  int wall_planes = 0;   // planes that voted in the histogram
};

// Normals are taken within this radius (voxels), the corner extractor's
// default (corner_extraction.h): they fit real walls of thick, noisy scans.
inline constexpr double kGravityNormalRadiusVoxels = 2.5;

// FailedPrecondition when no plane is within max_up_tilt_deg of vertical or
// no wall plane votes (the generator cannot run on this map). `surface`,
// when given, is grid's occupied voxels' index and normals (normals_grid.h),
// used when its radius is kGravityNormalRadiusVoxels.
StatusOr<GravityFrame> EstimateGravityFrame(const VoxelGrid& grid, const GravityParams& params,
                                            const internal::GridSurface* surface = nullptr);

// Yaw candidates (radians, about +z after levelling) that rotate b's walls
// onto a's: the top yaw_peaks peaks of the circular correlation of the two
// histograms, each followed by its 180 deg twin. Best first.
std::vector<double> YawCandidates(const GravityFrame& a, const GravityFrame& b,
                                  const GravityParams& params);

}  // namespace mapd::voxel

#endif  // MAPD_VOXEL_GRAVITY_ALIGNMENT_H_
