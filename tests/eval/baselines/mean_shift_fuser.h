// Competing algorithm 1 of the feature-fusion paper (Li et al. 2023, section
// 2.1): line-segment merging by mean-shift clustering (Lakaemper, IROS 2009),
// as docs/algorithms.md A.13 "Baselines" restates it:
//  1. mean shift on the segments' orientations (axial, period pi);
//  2. within each orientation mode, mean shift on the segments' centres;
//  3. each cluster is merged by projecting its segments onto a representative
//     line through the middle of the cluster: through the mean of the member
//     centres, along the members' mean (axial) orientation, unweighted.
// Registry name "mean_shift".
#ifndef MAPD_EVAL_BASELINES_MEAN_SHIFT_FUSER_H_
#define MAPD_EVAL_BASELINES_MEAN_SHIFT_FUSER_H_

#include "eval/baselines/batch_fuser.h"
#include "eval/baselines/mean_shift.h"

namespace mapd::fusion::baselines {

struct MeanShiftFuserParams {
  OrientationShiftParams orientation;  // step 1 (Gaussian, h = 2 deg)
  CentreShiftParams centre;            // step 2 (flat, h = 1.5 m)
  PostParams post;
};

class MeanShiftFuser : public BatchFuser {
 public:
  explicit MeanShiftFuser(const MeanShiftFuserParams& params)
      : BatchFuser(params.post), params_(params) {}
  const char* name() const override { return "mean_shift"; }

 protected:
  std::vector<std::vector<uint32_t>> Cluster(const std::vector<Member>& members) const override;
  geometry::Line2 MergeLine(const std::vector<Member>& members,
                            const std::vector<uint32_t>& cluster) const override;

 private:
  MeanShiftFuserParams params_;
};

}  // namespace mapd::fusion::baselines

#endif  // MAPD_EVAL_BASELINES_MEAN_SHIFT_FUSER_H_
