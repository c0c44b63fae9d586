// CheckMergeEvidence and DecideMerge (merge.h): the one rule the service and
// the benchmark apply to a merge's outcome before they count it as a merge.
#include <algorithm>
#include <string>
#include <vector>

#include "voxel/merge.h"

namespace mapd::voxel {

Status CheckMergeEvidence(const MergeOutcome& outcome, const std::vector<double>& resolutions_m,
                          const MergeParams& params) {
  if (resolutions_m.empty() || outcome.alignments.size() != resolutions_m.size()) {
    return Status::Internal("the merge returned " + std::to_string(outcome.alignments.size()) +
                            " alignments for " + std::to_string(resolutions_m.size()) + " inputs");
  }
  const double finest = *std::min_element(resolutions_m.begin(), resolutions_m.end());
  for (size_t i = 1; i < outcome.alignments.size(); ++i) {
    const Alignment& a = outcome.alignments[i];
    const std::string which = "submap " + std::to_string(a.id);
    // Correlation, plan-view and 180 deg turn hypotheses have no corners of
    // their own (docs/algorithms.md B.9); they passed the gates below.
    if (a.by_corners && a.matched_corners < params.min_matched_corners) {
      return Status::FailedPrecondition(which + ": " + std::to_string(a.matched_corners) +
                                        " matched corners, merge.min_matched_corners is " +
                                        std::to_string(params.min_matched_corners));
    }
    if (!(a.overlap_score >= params.min_overlap_score)) {
      return Status::FailedPrecondition(
          which + ": overlap score " + std::to_string(a.overlap_score) +
          " below merge.min_overlap_score " + std::to_string(params.min_overlap_score));
    }
    if (!(a.residual_m <= params.max_residual_voxels * finest * (1 + 1e-9))) {
      return Status::FailedPrecondition(which + ": residual " + std::to_string(a.residual_m) +
                                        " m above merge.max_residual_voxels " +
                                        std::to_string(params.max_residual_voxels) + " voxels");
    }
  }
  if (outcome.merged_bt.empty()) return Status::Internal("the merge returned no merged map");
  return Status::Ok();
}

MergeDecision DecideMerge(const StatusOr<MergeOutcome>& outcome, const std::vector<uint64_t>& ids,
                          const std::vector<double>& resolutions_m, const MergeParams& params,
                          bool review) {
  MergeDecision decision;
  if (!outcome.ok()) {
    decision.reason = outcome.status();
    return decision;
  }
  decision.reason = CheckMergeEvidence(*outcome, resolutions_m, params);
  if (!decision.reason.ok()) return decision;
  for (const uint64_t id : ids) {
    const auto it = std::find_if(outcome->alignments.begin(), outcome->alignments.end(),
                                 [&](const Alignment& a) { return a.id == id; });
    if (it == outcome->alignments.end()) {
      decision.reason =
          Status::Internal("the merge returned no alignment for submap " + std::to_string(id));
      decision.T_ref_input.clear();
      return decision;
    }
    decision.T_ref_input.push_back(it->T_reference_submap);
  }
  decision.verdict = review ? MergeVerdict::kProposed : MergeVerdict::kAccepted;
  return decision;
}

}  // namespace mapd::voxel
