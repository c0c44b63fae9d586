#include <cmath>
#include <string>

#include "voxel/merge.h"

namespace mapd::voxel {

Status MergeParams::Validate() const {
  if (min_matched_corners < 3) {
    return Status::InvalidArgument("min_matched_corners must be >= 3 (a rigid transform needs 3)");
  }
  if (!(max_residual_voxels > 0) || !std::isfinite(max_residual_voxels)) {
    return Status::InvalidArgument("max_residual_voxels must be finite and > 0");
  }
  if (!(min_overlap_score >= 0 && min_overlap_score <= 1)) {
    return Status::InvalidArgument("min_overlap_score must be in [0, 1]");
  }
  if (!(min_support_fraction >= 0 && min_support_fraction <= 1) ||
      !(ambiguous_support_ratio >= 0 && ambiguous_support_ratio <= 1)) {
    return Status::InvalidArgument(
        "min_support_fraction and ambiguous_support_ratio must be in [0, 1]");
  }
  if (!(ambiguous_overlap_margin >= 0 && ambiguous_overlap_margin <= 1)) {
    return Status::InvalidArgument("ambiguous_overlap_margin must be in [0, 1]");
  }
  if (!(min_shared_free_ratio >= 0) || !std::isfinite(min_shared_free_ratio)) {
    return Status::InvalidArgument("min_shared_free_ratio must be finite and >= 0");
  }
  if (fusion_rule != FusionRule::kOverlapRule && fusion_rule != FusionRule::kLogOdds) {
    return Status::InvalidArgument("fusion_rule is not a known rule");
  }
  if (resolution_policy != ResolutionPolicy::kRefuse &&
      resolution_policy != ResolutionPolicy::kResampleToFinest) {
    return Status::InvalidArgument("resolution_policy is not a known policy");
  }
  if (!(max_seconds > 0) || !std::isfinite(max_seconds)) {
    return Status::InvalidArgument("max_seconds must be finite and > 0");
  }
  if (threads < 1 || threads > 256) {
    return Status::InvalidArgument("threads must be in [1, 256], got " + std::to_string(threads));
  }
  if (!(consistency_distance_voxels > 0) || !std::isfinite(consistency_distance_voxels)) {
    return Status::InvalidArgument("consistency_distance_voxels must be finite and > 0");
  }
  if (max_match_attempts < 1) {
    return Status::InvalidArgument("max_match_attempts must be >= 1");
  }
  if (!(icp_screen_residual_factor >= 1) || !std::isfinite(icp_screen_residual_factor)) {
    return Status::InvalidArgument("icp_screen_residual_factor must be finite and >= 1");
  }
  if (icp_screen_iterations < 1) {
    return Status::InvalidArgument("icp_screen_iterations must be >= 1");
  }
  if (!(restart_turn_deg > 0 && restart_turn_deg <= 10)) {
    return Status::InvalidArgument("restart_turn_deg must be in (0, 10]");
  }
  if (!(lattice_snap_deg >= 0 && lattice_snap_deg <= 5)) {
    return Status::InvalidArgument("lattice_snap_deg must be in [0, 5]");
  }
  if (!(max_restart_spread_voxels >= 0) || !std::isfinite(max_restart_spread_voxels)) {
    return Status::InvalidArgument("max_restart_spread_voxels must be finite and >= 0");
  }
  for (std::size_t i = 0; i < looser_tolerances.size(); ++i) {
    const MatchTolerances& t = looser_tolerances[i];
    if (!(t.signature_deg >= 0 && t.signature_deg <= 180) ||
        !(t.normal_deg >= 0 && t.normal_deg <= 180)) {
      return Status::InvalidArgument("looser_tolerances[" + std::to_string(i) +
                                     "]: angles must be in [0, 180] degrees");
    }
  }
  if (!(distinct_rotation_deg > 0 && distinct_rotation_deg <= 180) ||
      !(distinct_translation_voxels > 0) || !std::isfinite(distinct_translation_voxels)) {
    return Status::InvalidArgument(
        "distinct_rotation_deg must be in (0, 180] and distinct_translation_voxels finite and > 0");
  }
  if (uniqueness_corner_attempts < 0) {
    return Status::InvalidArgument("uniqueness_corner_attempts must be >= 0");
  }
  Status status = gravity.Validate();
  if (!status.ok()) return status;
  status = correlation.Validate();
  if (!status.ok()) return status;
  status = corners.Validate();
  if (!status.ok()) return Status::InvalidArgument("corners." + status.message());
  status = matching.Validate();
  if (!status.ok()) return Status::InvalidArgument("matching." + status.message());
  return icp.Validate();
}

}  // namespace mapd::voxel
