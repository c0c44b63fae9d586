// One pairwise merge attempt of the pipeline (docs/algorithms.md B.4, B.5): corner
// matching with the overlap tie-break, ICP refinement, and the acceptance
// test of MergeParams. Internal to merge*.cc.
#ifndef MAPD_VOXEL_MERGE_PAIR_H_
#define MAPD_VOXEL_MERGE_PAIR_H_

#include <Eigen/Geometry>
#include <cstdint>

#include "common/status.h"
#include "voxel/corner.h"
#include "voxel/merge.h"
#include "voxel/voxel_grid.h"

namespace mapd::voxel {

class SubmapFeatures;

// One submap of the pair: its voxels, and its corners and gravity frame,
// computed on first use (submap_features.h).
struct PairSide {
  uint64_t id = 0;
  const VoxelGrid* grid = nullptr;
  SubmapFeatures* features = nullptr;
};

// B.5, shared by both hypothesis generators: the ICP screen, ICP from
// T_initial and the acceptance gates. Sets report's T_a_b, residual_m,
// overlap_score, icp_iterations and accepted or reason; adds its seconds to
// times->alignment_s. Errors only for bad input.
Status RefineAndGate(const PairSide& a, const PairSide& b, const MergeParams& params,
                     const Eigen::Isometry3d& T_initial, double finest_resolution_m,
                     StageTimes* times, PairReport* report);

// Aligns b to a. A refusal (weak evidence) is an OK result with
// accepted == false and the reason, e.g. "only 2 matched corners, need 4",
// "overlap score 0.12 below 0.30", "residual 0.25 m (2.5 voxels) above 2.0
// voxels". Errors only for bad parameters or input. Adds its seconds to
// times->matching_s and times->alignment_s. `finest_resolution_m` sets the
// voxel unit of the corner and ICP distances; the residual gate is in voxels
// of the coarser of the two maps (merge.h). `seconds_left` caps the corner search.
//
// Every generator's hypotheses pass the uniqueness gate too: two distinct
// accepted hypotheses refuse the pair naming both. Corner matching's first
// correlation.after_corner_stages tolerance stages run first (none by
// default); then the correlation generator when they accepted nothing (or
// always, with correlation.check_corner_solutions); then the remaining
// stages when nothing was accepted yet (after a search that refused, the
// strict one only). A refusal names what every stage found.
StatusOr<PairReport> AlignPair(const PairSide& a, const PairSide& b, const MergeParams& params,
                               double finest_resolution_m, double seconds_left, StageTimes* times);

}  // namespace mapd::voxel

#endif  // MAPD_VOXEL_MERGE_PAIR_H_
