// Refines the wall-histogram yaw candidates (gravity_alignment.h) before the
// 3D translation search (correlation_search.h; docs/algorithms.md B.9).
//
// Outdoors the wall histograms are poor: on the benchmark's campus crops the
// candidate nearest the truth was 4-11 deg off in 5 of 6 pairs at 20 %
// overlap, and the 3D search, which ranks the true shift first when given
// the true yaw, then found nothing ICP could finish. The 3D search is too
// costly to sweep the yaw, a plan view is not: both levelled maps are
// reduced to columns (pixels of a horizontal grid) that hold upright
// structure, and for each yaw near a candidate the best normalised 2D
// correlation of the two column images over all shifts scores that yaw.
// The best yaw of each candidate's window is added to the candidates, not
// put in their place: indoors the histograms are right to a degree and the
// plan view is not (fr_078_tidyup at 10 % overlap: every right candidate
// moved 3-12 deg, as the overlap strip is below min_overlap_fraction), and
// the 3D search ranks the yaws of both sources on one score.
//
// A column holds structure when at least min_voxels_in_band of its occupied
// voxels lie between band_low_m (exclusive) and band_high_m above its lowest
// one: trunks, walls and hedges, not ground or floors.
//
// Thread safety: reentrant.
#ifndef MAPD_VOXEL_YAW_REFINEMENT_H_
#define MAPD_VOXEL_YAW_REFINEMENT_H_

#include <Eigen/Geometry>
#include <cstddef>
#include <vector>

#include "common/status.h"
#include "voxel/voxel_grid.h"

namespace mapd::voxel {

struct YawRefinementParams {
  bool enabled = true;
  // Each candidate is searched within +-window_deg: first every coarse_step_deg,
  // then every 1 deg within one coarse step of the best.
  double window_deg = 12.0;
  double coarse_step_deg = 3.0;
  // Column edge in voxels of the finer map. On the campus crops (0.2 m
  // voxels) 2 voxels ranked the true yaw first in 6 of 6 pairs at 20 %
  // overlap; 4 voxels in 1 of 6.
  double pixel_voxels = 2.0;
  // Cap on the padded image; larger maps get larger columns. The campus
  // crops need ~0.45M pixels; 2M hold ~100 MiB of buffers.
  std::size_t max_pixels = 2'000'000;
  // The height band (metres above a column's lowest voxel). On the campus
  // crops 2-100 m, 1-2 m and 0.5-2 m all refined the candidates nearest the
  // truth to within 1 deg in 6 of 6 pairs at 20 % overlap.
  double band_low_m = 2.0;
  double band_high_m = 100.0;
  int min_voxels_in_band = 3;
  // Shifts where either image has fewer structure columns than this share
  // of the smaller one inside the other's data are not scored. At 5 %
  // shifts that put a map's edge on the other's edge outscored the truth.
  double min_overlap_fraction = 0.15;
  // A best yaw closer than this to its candidate is not added (ICP finishes
  // a degree or two).
  double min_change_deg = 2.0;
  // At most this many are added, best 2D score first: each added yaw costs
  // the 3D search one more yaw (~1.5 s on a 150 m outdoor crop), and adding
  // all four took new_college merges from ~10 to ~15 s of CPU.
  int max_added = 2;

  Status Validate() const;
};

struct YawRefinementStats {
  int yaws_scored = 0;
  int yaws_added = 0;
  double pixel_m = 0.0;
  // Per input yaw: the 2D score at it and the best in its window (empty
  // when nothing was scored).
  std::vector<double> candidate_scores, window_scores;
  // Per input yaw: the window's best yaw and the plan-view shift that
  // scored best there, as the horizontal translation t (metres) of
  // x_a' = Rz(yaw) R_b x_b + t in a's levelled frame (x and y only; NaN
  // when b had no structure column at that yaw). For
  // pairs whose 3D search would be large, the merge starts ICP there first
  // (CorrelationParams::plan_view_first_min_cells).
  std::vector<double> window_yaws;
  std::vector<Eigen::Vector2d> window_shifts_m;
};

// R_a, R_b level each map (R * up = +z); a yaw turns levelled b about +z, as
// in SearchTranslations. Returns the candidates followed by the best yaws of
// the candidates' windows that lie min_change_deg or more from their
// candidate, at most max_added of them, best first (none when a map has no
// structure column). InvalidArgument for bad params. The candidates' windows
// are scored on up to `threads` threads (MergeParams::threads); the result
// does not depend on the count.
StatusOr<std::vector<double>> RefineYaws(const VoxelGrid& a, const Eigen::Matrix3d& R_a,
                                         const VoxelGrid& b, const Eigen::Matrix3d& R_b,
                                         const std::vector<double>& yaws,
                                         double finest_resolution_m,
                                         const YawRefinementParams& params,
                                         YawRefinementStats* stats, int threads = 1);

// The height that completes a plan-view placement: for b levelled by R_b,
// turned by `yaw` about +z and moved by the horizontal translation t_m (as
// in window_shifts_m), the vertical translation that puts b's columns on
// a's: the median, over the columns (pixel_m squares) where both maps have
// occupied voxels, of a's lowest voxel's height minus b's. One per
// placement; NaN where no column is shared. On the benchmark's campus crops
// the starts it completes were 0.48-1.30 m from the truth at B's centroid
// (docs/voxel-merge.md). The placements run on `threads` threads (the same
// heights on any number).
std::vector<double> PlanViewHeights(const VoxelGrid& a, const Eigen::Matrix3d& R_a,
                                    const VoxelGrid& b, const Eigen::Matrix3d& R_b,
                                    const std::vector<double>& yaws,
                                    const std::vector<Eigen::Vector2d>& t_m, double pixel_m,
                                    int threads = 1);

}  // namespace mapd::voxel

#endif  // MAPD_VOXEL_YAW_REFINEMENT_H_
