// Competing algorithm 2 of the feature-fusion paper (Li et al. 2023, section
// 2.2): line-segment merging by density clustering (Sarkar, Pal & Sarkar, RAS
// 2014), as docs/algorithms.md A.13 "Baselines" restates it:
//  1. mean shift on the segments' orientations (axial, period pi);
//  2. within each orientation mode, density-based clustering (DBSCAN) where two
//     segments are neighbours when they are close in
//       - lateral separation: max of the distances of each midpoint to the
//         other's infinite line <= lateral_m, and
//       - longitudinal overlap: the overlap of their projections onto their mean
//         direction >= min_overlap_m (negative: a gap of up to -min_overlap_m);
//     DBSCAN noise (not density-reachable from a core segment) stays a cluster of one;
//  3. each cluster is merged with length weights: the line through the
//     length-weighted mean of the midpoints, along the length-weighted mean
//     orientation; endpoints are the extreme projections of the members.
// Registry name "density".
#ifndef MAPD_EVAL_BASELINES_DENSITY_FUSER_H_
#define MAPD_EVAL_BASELINES_DENSITY_FUSER_H_

#include <cstdint>

#include "eval/baselines/batch_fuser.h"
#include "eval/baselines/mean_shift.h"

namespace mapd::fusion::baselines {

struct DensityFuserParams {
  OrientationShiftParams orientation;  // step 1 (Gaussian, h = 2 deg)
  double lateral_m = 0.3;              // step 2: max lateral separation (as eta)
  double min_overlap_m = 0.0;          // step 2: min longitudinal overlap
  uint32_t min_pts = 2;                // step 2: DBSCAN core size, the segment included
  PostParams post;
};

// Step 2's neighbour test, symmetric in (f, g).
bool DensityNeighbours(const geometry::Segment2& f, const geometry::Segment2& g, double lateral_m,
                       double min_overlap_m);

class DensityFuser : public BatchFuser {
 public:
  explicit DensityFuser(const DensityFuserParams& params)
      : BatchFuser(params.post), params_(params) {}
  const char* name() const override { return "density"; }

 protected:
  std::vector<std::vector<uint32_t>> Cluster(const std::vector<Member>& members) const override;
  geometry::Line2 MergeLine(const std::vector<Member>& members,
                            const std::vector<uint32_t>& cluster) const override;

 private:
  DensityFuserParams params_;
};

}  // namespace mapd::fusion::baselines

#endif  // MAPD_EVAL_BASELINES_DENSITY_FUSER_H_
