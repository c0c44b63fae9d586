// The second hypothesis generator's second half (docs/algorithms.md B.9): for
// each yaw candidate, the translations that best put b's levelled map into
// a's, by a 3D correlation on a coarse grid computed with FFTs (FFTW3).
//
// The score of a translation t rewards b's occupied cells on a's occupied
// cells and penalises them on a's free cells (and a's occupied cells on b's
// free cells):
//   S(t) = corr(occA, occB)(t) - w * (corr(freeA, occB)(t) + corr(occA, freeB)(t)),
// normalised by the occupied cells each map has inside the other's data.
// Plain occupancy correlation prefers the 180 deg flip of a symmetric
// corridor (its walls coincide as well as the true ones); the flip puts
// furniture and side rooms into the other map's observed free space, which
// the penalty counts. Space either map never observed counts neither way.
//
// The grids and FFTs are single precision (FFTW3's fftwf): they hold 0/1
// and shares of a cell, and the scores are only ranked.
//
// Thread safety: reentrant (FFTW's planner, which is not, is serialised
// inside).
#ifndef MAPD_VOXEL_CORRELATION_SEARCH_H_
#define MAPD_VOXEL_CORRELATION_SEARCH_H_

#include <Eigen/Geometry>
#include <cstddef>
#include <vector>

#include "common/status.h"
#include "voxel/voxel_grid.h"
#include "voxel/yaw_refinement.h"

namespace mapd::voxel {

struct CorrelationParams {
  // Run the generator at all.
  bool enabled = true;
  // When it runs: after this many of corner matching's tolerance stages
  // (MergeParams: the strict one, then looser_tolerances) have accepted
  // nothing; the remaining stages run only when it accepts nothing too.
  // 0 (the default): the generator first; corners are extracted only when it
  // accepts nothing. On the benchmark's 90 merges and 18 negative pairs every
  // outcome was the same as with corner matching first, at 30-45 % less CPU
  // indoors: corner extraction and matching were a third to a half of an indoor merge
  // (docs/archive/voxel-merge-history.md, "Correlation first"). It was 1 until the shared
  // free space gate (MergeParams::min_shared_free_ratio): the generator's
  // peaks that put a room's floor on the other room's ceiling passed every
  // other gate in the test scenes. 1: the strict corner stage first, then
  // the generator as a check on what it accepted (check_corner_solutions).
  // A large value (e.g. 100): after every stage.
  int after_corner_stages = 0;
  // Whether the looser corner stages still run when the
  // generator ran and accepted nothing. Off: on the benchmark's 90 merges and
  // 18 negative pairs (docs/voxel-merge.md, "Refusals") they placed nothing
  // the generator had not, every outcome was the same without them, and they
  // were half of a refusal's CPU. They always run when the generator could
  // not (no floor or wall plane to level or turn by) or is disabled.
  bool looser_stages_after_refusal = false;
  // Also run it after corner matching accepted a solution (in the stages
  // before it), so that the uniqueness gate sees the other yaws too; then only the best peak of
  // each yaw that is distinct from the accepted answer is refined (every hypothesis refined cost
  // ~4x the whole corner merge on geb079; docs/voxel-merge.md gives the cost of this check).
  bool check_corner_solutions = true;
  // Coarse cell edge in voxels of the finer map: coarse enough that a wall
  // rasterised in two rotated grids lands in the same or a neighbouring cell
  // and the FFTs stay small, fine enough that a peak starts ICP within its
  // basin (ICP converges from a few voxels).
  double cell_voxels = 3.0;
  // Cap on the padded FFT grid; larger maps get coarser cells. Indoor
  // submaps of 150k voxels need 0.9-1.6M cells; 150k-voxel outdoor maps (the
  // campus crops, 71-132 m across at 0.2 m) need 11.5-16M for cells of 3
  // voxels, and at the 2M cap (before) their 1.3 m cells ranked the true
  // shift below 190th (coarse cells of trees and hedges match anything;
  // docs/voxel-merge.md). Single precision,
  // 16M cells take ~40 bytes each (~600 MiB) and ~1.5 s per yaw here.
  std::size_t max_cells = 16'000'000;
  // w in S(t) above. A conflict (a wall where the other map saw through) is
  // strong evidence and rare: free space within a cell of either map's
  // walls does not count, so few cells are left to conflict. In the
  // corridor test fixture (tests/voxel/support/corridor_scene.h) the true
  // placement ranks 5th at any w from 1 to 20 and 14th at 0, where the flip
  // and slides of b along the corridor (more wall on wall) win. (On an
  // earlier grid placement: 1st at 10, 23rd at 5, below 60th at 1.)
  double free_weight = 10.0;
  // A map has data within this of its occupied voxels (or where it is
  // free): the score is normalised by the occupied cells each map has inside
  // the other's data (a cosine of the overlap), so sliding a corridor over
  // more of the other map does not win by adding wall. 1 m: sensors see
  // surfaces from the free space in front of them.
  double coverage_radius_m = 1.0;
  // Shifts where either map has fewer occupied cells than this share of the
  // smaller map inside the other's data are not scored (chance agreement).
  double min_overlap_fraction = 0.05;
  // Translation peaks per yaw and hypotheses kept over all yaws (best S
  // first); every kept hypothesis goes through the ICP screen and gates.
  int peaks_per_yaw = 3;
  int max_hypotheses = 12;
  // Peaks closer than this (coarse cells) are one.
  double min_peak_separation_cells = 3.0;
  // Before the search, the best yaws near the candidates in a plan view of
  // the two maps are added to them (yaw_refinement.h; RunCorrelation in
  // merge_hypotheses.cc tries their peaks after the candidates').
  YawRefinementParams yaw_refinement;
  // Pairs whose grid at cell_voxels would exceed this many cells (the
  // benchmark's campus crops: 11.5-16M; its indoor crops: 0.9-1.9M) are
  // placed by the plan view first: each window's best placement
  // (YawRefinementStats::window_shifts_m, with PlanViewHeights) goes through
  // the ICP screen and the gates, and if one passes, the 3D search runs at
  // its yaw and that yaw's 180 deg twin alone, for the uniqueness gate (a
  // slide at the answer's yaw, a flip at the twin); if none passes, at every
  // yaw as below. Outdoors the plan view starts ICP as near the truth as the
  // 3D search's peaks, and the search is most of a merge's CPU
  // (docs/voxel-merge.md). 0: every pair.
  std::size_t plan_view_first_min_cells = 6'000'000;

  Status Validate() const;
};

// One initial transform for ICP.
struct CorrelationHypothesis {
  Eigen::Isometry3d T_a_b = Eigen::Isometry3d::Identity();
  double yaw_rad = 0.0;  // the yaw candidate it came from
  double score = 0.0;    // S(t) normalised (coverage_radius_m), about [-w, 1]
};

struct CorrelationStats {
  int yaws = 0;
  double cell_m = 0.0;
  std::size_t grid_cells = 0;  // padded FFT grid
};

// The cells of SearchTranslations' padded grid for these maps and yaws at
// params.cell_voxels, before max_cells coarsens it (0 for an empty map or no
// yaw).
std::size_t CorrelationGridCells(const VoxelGrid& a, const Eigen::Matrix3d& R_a, const VoxelGrid& b,
                                 const Eigen::Matrix3d& R_b, const std::vector<double>& yaws,
                                 double finest_resolution_m, const CorrelationParams& params);

// R_a, R_b level each map (R * up = +z); every yaw turns levelled b about +z.
// Hypotheses best first, at most max_hypotheses. InvalidArgument for bad
// params; ResourceExhausted if even the coarsest allowed cell exceeds
// max_cells (never for maps within VoxelGrid's key range and max_cells >= 1000).
// The FFTs' passes run on `threads` threads (MergeParams::threads; RealFft).
StatusOr<std::vector<CorrelationHypothesis>> SearchTranslations(
    const VoxelGrid& a, const Eigen::Matrix3d& R_a, const VoxelGrid& b, const Eigen::Matrix3d& R_b,
    const std::vector<double>& yaws, double finest_resolution_m, const CorrelationParams& params,
    CorrelationStats* stats, int threads = 1);

}  // namespace mapd::voxel

#endif  // MAPD_VOXEL_CORRELATION_SEARCH_H_
