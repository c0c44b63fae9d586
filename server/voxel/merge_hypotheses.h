// Internal to merge_pair.cc: the correlation generator's run for one pair
// (docs/algorithms.md B.9) and the uniqueness gate's helpers.
#ifndef MAPD_VOXEL_MERGE_HYPOTHESES_H_
#define MAPD_VOXEL_MERGE_HYPOTHESES_H_

#include <Eigen/Geometry>
#include <string>
#include <vector>

#include "common/status.h"
#include "voxel/merge.h"
#include "voxel/merge_pair.h"

namespace mapd::voxel {

// A hypothesis that went through RefineAndGate: where it came from and how
// it ended.
struct TriedHypothesis {
  std::string label;  // "corner solution 2", "correlation yaw 93.1 deg, peak 1"
  PairReport report;
};

struct CorrelationRun {
  std::vector<TriedHypothesis> tried;
  int plan_view = 0;    // plan-view placements refined (large grids)
  int generated = 0;    // hypotheses from the FFT search
  int yaws = 0;         // yaws the FFT search ran at
  int agreeing = 0;     // skipped: they start where an accepted answer already is
  std::string not_run;  // why the generator could not run (no floor, no walls)
};

// Levels both maps, takes the yaw candidates and the FFT translation peaks,
// and refines every peak not already near one of `accepted` (uniqueness
// thresholds) with RefineAndGate. On grids above
// correlation.plan_view_first_min_cells the plan view's placements are
// refined first, and once one passes, the FFT search runs at its yaw and
// that yaw's 180 deg twin alone. Adds its seconds to times->correlation_s
// (and ICP's to alignment_s).
StatusOr<CorrelationRun> RunCorrelation(const PairSide& a, const PairSide& b,
                                        const MergeParams& params, double finest_resolution_m,
                                        const std::vector<Eigen::Isometry3d>& accepted,
                                        StageTimes* times);

// True when the two transforms differ by more than the uniqueness gate's
// thresholds; the translation is compared at `centroid_b` (B's frame).
bool DistinctTransforms(const Eigen::Isometry3d& x, const Eigen::Isometry3d& y,
                        const Eigen::Vector3d& centroid_b, const MergeParams& params,
                        double finest_resolution_m);

// The uniqueness gate's test of `h` against the answer `best` (both passed
// every gate, and they are distinct): `h` makes the pair ambiguous when its
// support is at least ambiguous_support_ratio of the best's, or its overlap
// score at least ambiguous_overlap_margin above the best's (merge.h).
bool IsRival(const PairReport& best, const PairReport& h, const MergeParams& params);

// e.g. "corner solution 1 (rotation 93.2 deg, translation (1.20, -3.40, 0.02) m,
// residual 0.62 voxels, overlap 0.97)"
std::string DescribeHypothesis(const TriedHypothesis& h, double finest_resolution_m);

}  // namespace mapd::voxel

#endif  // MAPD_VOXEL_MERGE_HYPOTHESES_H_
