#include "voxel/merge_pair.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "common/clock.h"
#include "voxel/icp.h"
#include "voxel/merge_overlap.h"

namespace mapd::voxel {
namespace {

std::string Fixed(double value, int digits) {
  char buffer[64];
  std::snprintf(buffer, sizeof(buffer), "%.*f", digits, value);
  return buffer;
}

// e.g. "residual 0.320 m (1.60 voxels) above 0.75 voxels"
std::string ResidualReason(double residual_m, double residual_voxels, double max_voxels) {
  return "residual " + Fixed(residual_m, 3) + " m (" + Fixed(residual_voxels, 2) +
         " voxels) above " + Fixed(max_voxels, 2) + " voxels";
}

// One corner solution: the maximum clique (minus `matching.excluded_pairs`),
// Umeyama, ICP, the acceptance gates. `correspondences` gets the clique used.
StatusOr<PairReport> TrySolution(const PairSide& a, const PairSide& b, const MergeParams& params,
                                 const CornerMatchingParams& matching, double finest_resolution_m,
                                 StageTimes* times, std::vector<CornerPair>* correspondences) {
  PairReport report;
  report.id_a = a.id;
  report.id_b = b.id;
  // The residual gate's unit: a voxel of the COARSER map of the pair. The RMS
  // of a right alignment is set by how coarsely the surfaces were rasterised:
  // a 10 cm room map on a 5 cm one ends at 0.43 coarse voxels, 0.87 fine ones
  // (merge_test.cc: refused by a gate in fine voxels), near the ~0.5 voxel of
  // two maps of one resolution. Metres would need a setting per resolution.
  // Equal resolutions: the same unit as before.
  const double gate_voxel_m = std::max(a.grid->resolution(), b.grid->resolution());
  const std::string gate_unit =
      a.grid->resolution() == b.grid->resolution()
          ? ""
          : " (voxels of the coarser map, " + Fixed(gate_voxel_m, 3) + " m)";

  // B.4: corners, the maximum clique, Umeyama; ties go to the transform that
  // makes the most occupied voxels coincide (the paper, section IV.C).
  auto start = std::chrono::steady_clock::now();
  const TransformScore tie_score = [&](const Eigen::Isometry3d& T_a_b) {
    return static_cast<double>(
        ComputeOverlapScore(*a.grid, *b.grid, T_a_b, params.tie_break_points).coinciding);
  };
  auto match = MatchCorners(*a.corners, *b.corners, matching, tie_score);
  times->matching_s += SecondsSince(start);
  if (!match.ok()) return match.status();
  correspondences->clear();
  report.matched_corners = match->transform_valid ? match->matched_count : 0;
  if (!match->transform_valid || match->matched_count < params.min_matched_corners) {
    report.reason = "only " + std::to_string(match->transform_valid ? match->matched_count : 0) +
                    " matched corners, need " + std::to_string(params.min_matched_corners);
    return report;
  }
  *correspondences = match->correspondences;
  for (const CornerPair& p : match->correspondences) {
    report.matched_a_b.emplace_back((*a.corners)[static_cast<std::size_t>(p.a)].position,
                                    (*b.corners)[static_cast<std::size_t>(p.b)].position);
  }
  report.T_a_b = match->T_a_b;

  // B.5: ICP on the occupied voxel centres of the overlap, then acceptance.
  // First on a small subsample (icp_screen_points): a wrong solution drifts
  // for up to max_iterations, at a fifth of the cost; only a screen ending
  // within icp_screen_residual_factor of the gate is refined on all points.
  start = std::chrono::steady_clock::now();
  Eigen::Isometry3d T_start = match->T_a_b;
  if (params.icp_screen_points > 0 && params.icp_screen_points < params.icp.max_source_points) {
    IcpParams screen_params = params.icp;
    screen_params.max_source_points = params.icp_screen_points;
    auto screen = RefineIcp(a.grid->occupied_centres(), b.grid->occupied_centres(), match->T_a_b,
                            finest_resolution_m, screen_params);
    if (screen.ok()) {
      const double screen_voxels = screen->rms_residual_m / gate_voxel_m;
      if (screen_voxels > params.icp_screen_residual_factor * params.max_residual_voxels) {
        times->alignment_s += SecondsSince(start);
        report.T_a_b = screen->T_target_source;
        report.residual_m = screen->rms_residual_m;
        report.icp_iterations = screen->iterations;
        report.reason =
            ResidualReason(screen->rms_residual_m, screen_voxels, params.max_residual_voxels) +
            gate_unit + " (on " + std::to_string(screen->source_points) + " points)";
        return report;
      }
      T_start = screen->T_target_source;
    }
  }
  auto icp = RefineIcp(a.grid->occupied_centres(), b.grid->occupied_centres(), T_start,
                       finest_resolution_m, params.icp);
  if (!icp.ok()) {
    times->alignment_s += SecondsSince(start);
    if (icp.status().code() != StatusCode::kFailedPrecondition) return icp.status();
    report.reason = icp.status().message();
    return report;
  }
  report.T_a_b = icp->T_target_source;
  report.residual_m = icp->rms_residual_m;
  report.icp_iterations = icp->iterations;
  const OverlapScore overlap =
      ComputeOverlapScore(*a.grid, *b.grid, report.T_a_b, params.overlap_points);
  report.overlap_score = overlap.score;
  times->alignment_s += SecondsSince(start);

  const double residual_voxels = report.residual_m / gate_voxel_m;
  // A refinement still moving when it ran out of iterations has not shown
  // where it ends: new_college 0.7 trial 3 was accepted at 0.98 voxels while
  // still 0.65 deg / 3 voxels off after 50 iterations, and converged to the
  // right transform (0.53 voxel) after 85.
  if (!icp->converged) {
    report.reason = "ICP did not converge in " + std::to_string(icp->iterations) +
                    " iterations (residual " + Fixed(residual_voxels, 2) + " voxels)" + gate_unit;
    return report;
  }
  if (residual_voxels > params.max_residual_voxels) {
    report.reason =
        ResidualReason(report.residual_m, residual_voxels, params.max_residual_voxels) + gate_unit;
    return report;
  }
  if (report.overlap_score < params.min_overlap_score) {
    report.reason = "overlap score " + Fixed(report.overlap_score, 2) + " below " +
                    Fixed(params.min_overlap_score, 2);
    return report;
  }
  report.accepted = true;
  return report;
}

}  // namespace

StatusOr<PairReport> AlignPair(const PairSide& a, const PairSide& b, const MergeParams& params,
                               double finest_resolution_m, double seconds_left, StageTimes* times) {
  const auto start = std::chrono::steady_clock::now();
  std::vector<MatchTolerances> stages = {{params.matching.signature_tolerance_rad * 180.0 / M_PI,
                                          params.matching.normal_tolerance_rad * 180.0 / M_PI}};
  stages.insert(stages.end(), params.looser_tolerances.begin(), params.looser_tolerances.end());
  StatusOr<PairReport> first = Status::Internal("no attempt");
  int tried = 0;
  for (std::size_t stage = 0; stage < stages.size(); ++stage) {
    CornerMatchingParams matching = params.matching;
    matching.consistency_distance_m = params.consistency_distance_voxels * finest_resolution_m;
    matching.signature_tolerance_rad = stages[stage].signature_deg * M_PI / 180.0;
    matching.normal_tolerance_rad = stages[stage].normal_deg * M_PI / 180.0;
    for (int attempt = 0; attempt < params.max_match_attempts; ++attempt) {
      const double left = seconds_left - SecondsSince(start);
      if (tried > 0 && left <= 0) break;
      if (matching.max_search_seconds <= 0 || matching.max_search_seconds > left) {
        matching.max_search_seconds = std::max(left, 1e-3);
      }
      std::vector<CornerPair> used;
      StatusOr<PairReport> report =
          TrySolution(a, b, params, matching, finest_resolution_m, times, &used);
      ++tried;
      if (!report.ok() || report->accepted) return report;
      if (tried == 1) first = report;
      // Too few corners ends the stage; a solution that alignment refused is
      // excluded and the search rerun.
      if (used.empty()) break;
      for (const CornerPair& p : used) matching.excluded_pairs.emplace_back(p.a, p.b);
    }
  }
  // Refused: report the strict graph's maximum clique (the first solution).
  if (first.ok() && tried > 1) {
    first->reason +=
        " (first of " + std::to_string(tried) + " corner solutions tried, all refused)";
  }
  return first;
}

}  // namespace mapd::voxel
