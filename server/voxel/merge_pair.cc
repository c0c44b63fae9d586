#include "voxel/merge_pair.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "common/clock.h"
#include "voxel/icp.h"
#include "voxel/lattice_pose.h"
#include "voxel/merge_hypotheses.h"
#include "voxel/merge_overlap.h"
#include "voxel/parallel.h"
#include "voxel/submap_features.h"

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

// The ICP screen's params (a subsample, fewer iterations), or none when
// MergeParams turns screening off.
std::optional<IcpParams> ScreenParams(const MergeParams& params) {
  if (params.icp_screen_points == 0 || params.icp_screen_points >= params.icp.max_source_points) {
    return std::nullopt;
  }
  IcpParams screen = params.icp;
  screen.max_source_points = params.icp_screen_points;
  screen.max_iterations = std::min(params.icp_screen_iterations, params.icp.max_iterations);
  return screen;
}

// Where a restart is turned about: the centre of b's voxels that land in
// a's occupied box under T (the overlap), so the turned start keeps the
// overlap in place; b's centroid when none do.
Eigen::Vector3d OverlapCentre(const VoxelGrid& a, const VoxelGrid& b, const Eigen::Isometry3d& T) {
  const Eigen::AlignedBox3d box(a.min_corner(), a.max_corner());
  Eigen::Vector3d in_box = Eigen::Vector3d::Zero(), all = Eigen::Vector3d::Zero();
  std::size_t n = 0;
  for (const Eigen::Vector3d& c : b.occupied_centres()) {
    const Eigen::Vector3d p = T * c;
    all += p;
    if (box.contains(p)) {
      in_box += p;
      ++n;
    }
  }
  if (n > 0) return in_box / static_cast<double>(n);
  return all / static_cast<double>(std::max<std::size_t>(1, b.num_occupied()));
}

// MergeParams::max_restart_spread_voxels: how far (metres, at a corner of b's
// bounding box) the restarts that pass the residual gate end from T. Like the
// ICP of a hypothesis, first on icp_screen_points: a subsample's fit is noisy
// (right merges at 10 % overlap ended up to 4.4 voxels apart), so only when
// the screens spread beyond the limit are the restarts refined on all points
// (from where their screens ended) and judged again.
StatusOr<double> RestartSpread(const PairSide& a, const PairSide& b, const MergeParams& params,
                               const Eigen::Isometry3d& T, double finest_resolution_m,
                               double gate_voxel_m) {
  const IcpTarget& target = a.features->IcpIndex(finest_resolution_m);
  const std::vector<Eigen::Vector3d>& source = b.grid->occupied_centres();
  const Eigen::Vector3d lo = b.grid->min_corner(), hi = b.grid->max_corner();
  // How far `restarts` end from T; the failed and the refused do not count.
  const auto spread = [&](const std::vector<StatusOr<IcpResult>>& restarts) {
    double spread_m = 0.0;
    for (const StatusOr<IcpResult>& r : restarts) {
      if (!r.ok() || !r->converged ||
          r->rms_residual_m / gate_voxel_m > params.max_residual_voxels) {
        continue;
      }
      for (int c = 0; c < 8; ++c) {
        const Eigen::Vector3d q((c & 1) != 0 ? hi.x() : lo.x(), (c & 2) != 0 ? hi.y() : lo.y(),
                                (c & 4) != 0 ? hi.z() : lo.z());
        spread_m = std::max(spread_m, (r->T_target_source * q - T * q).norm());
      }
    }
    return spread_m;
  };
  // Runs ICP from each start, the starts on the merge's threads (each
  // result in its own slot: the same whatever the thread count);
  // FailedPrecondition (the overlap lost) is no rival, any other error is
  // returned.
  const auto run = [&](const std::vector<Eigen::Isometry3d>& starts, const IcpParams& icp_params,
                       std::vector<StatusOr<IcpResult>>* out) -> Status {
    out->assign(starts.size(), Status::Internal("not run"));
    ParallelFor(starts.size(), params.threads, [&](std::size_t i, std::size_t) {
      (*out)[i] = RefineIcp(target, source, starts[i], icp_params);
    });
    for (const StatusOr<IcpResult>& r : *out) {
      if (!r.ok() && r.status().code() != StatusCode::kFailedPrecondition) return r.status();
    }
    return Status::Ok();
  };

  const Eigen::Vector3d pivot = OverlapCentre(*a.grid, *b.grid, T);
  const double angle = params.restart_turn_deg * M_PI / 180.0;
  std::vector<Eigen::Isometry3d> starts;
  for (int axis = 0; axis < 3; ++axis) {
    for (const double sign : {-1.0, 1.0}) {
      Eigen::Isometry3d turn = Eigen::Isometry3d::Identity();
      turn.linear() = Eigen::AngleAxisd(sign * angle, Eigen::Vector3d::Unit(axis)).matrix();
      turn.translation() = pivot - turn.linear() * pivot;
      starts.push_back(turn * T);
    }
  }
  std::vector<StatusOr<IcpResult>> restarts;
  if (const std::optional<IcpParams> screen_params = ScreenParams(params)) {
    MAPD_RETURN_IF_ERROR(run(starts, *screen_params, &restarts));
    const double screened_m = spread(restarts);
    if (screened_m <= params.max_restart_spread_voxels * gate_voxel_m) return screened_m;
    for (std::size_t i = 0; i < starts.size(); ++i) {
      if (restarts[i].ok()) starts[i] = restarts[i]->T_target_source;
    }
  }
  MAPD_RETURN_IF_ERROR(run(starts, params.icp, &restarts));
  return spread(restarts);
}

// Issue 42 item 3 (voxel/lattice_pose.h): when the ICP answer lies within
// lattice_snap_deg of a lattice pose, the lattice poses around it are scored
// with ICP's own residual and the best replaces the answer if it fits at
// least as well. A copy merged with itself (or moved by whole voxels) then
// comes back exact, and its voxels fuse onto voxels without resampling. Every
// gate still judges the answer that is kept. Only for one resolution: the
// coarser map's voxel centres lie off the finer lattice.
void SnapToLattice(const PairSide& a, const PairSide& b, const MergeParams& params, double voxel_m,
                   PairReport* report) {
  constexpr double kPi = 3.14159265358979323846;
  const Eigen::Vector3d pivot_b =
      report->T_a_b.inverse() * OverlapCentre(*a.grid, *b.grid, report->T_a_b);
  const std::vector<Eigen::Isometry3d> poses =
      LatticePosesNear(report->T_a_b, pivot_b, voxel_m, params.lattice_snap_deg * kPi / 180.0);
  if (poses.empty()) return;
  const IcpTarget& target = a.features->IcpIndex(voxel_m);
  // The ICP answer scored on the same terms (the overlap judged from it).
  const auto answer = EvaluateIcp(target, b.grid->occupied_centres(), report->T_a_b, params.icp);
  if (!answer.ok()) return;
  // Every pose scored on the merge's threads, then taken in order (the
  // last of equal fits wins, as in one loop).
  std::vector<StatusOr<IcpResult>> fits(poses.size(), Status::Internal("not run"));
  ParallelFor(poses.size(), params.threads, [&](std::size_t i, std::size_t) {
    fits[i] = EvaluateIcp(target, b.grid->occupied_centres(), poses[i], params.icp);
  });
  double best_m = answer->rms_residual_m;
  std::optional<Eigen::Isometry3d> best;
  for (std::size_t i = 0; i < poses.size(); ++i) {
    const StatusOr<IcpResult>& fit = fits[i];
    if (fit.ok() && fit->inliers >= answer->inliers && fit->rms_residual_m <= best_m) {
      best_m = fit->rms_residual_m;
      best = poses[i];
    }
  }
  if (!best) return;
  report->T_a_b = *best;
  report->residual_m = best_m;
  report->on_lattice = true;
}

}  // namespace

Status RefineAndGate(const PairSide& a, const PairSide& b, const MergeParams& params,
                     const Eigen::Isometry3d& T_initial, double finest_resolution_m,
                     StageTimes* times, PairReport* report) {
  report->T_a_b = T_initial;
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
  auto start = std::chrono::steady_clock::now();
  // B.5: ICP on the occupied voxel centres of the overlap, then acceptance.
  // First on a small subsample (icp_screen_points): a wrong solution drifts
  // for up to max_iterations, at a fifth of the cost; only a screen ending
  // within icp_screen_residual_factor of the gate is refined on all points.
  Eigen::Isometry3d T_start = T_initial;
  if (const std::optional<IcpParams> screen_params = ScreenParams(params)) {
    auto screen = RefineIcp(a.features->IcpIndex(finest_resolution_m), b.grid->occupied_centres(),
                            T_initial, *screen_params);
    if (screen.ok()) {
      const double screen_voxels = screen->rms_residual_m / gate_voxel_m;
      if (screen_voxels > params.icp_screen_residual_factor * params.max_residual_voxels) {
        times->alignment_s += SecondsSince(start);
        report->T_a_b = screen->T_target_source;
        report->residual_m = screen->rms_residual_m;
        report->icp_iterations = screen->iterations;
        report->reason =
            ResidualReason(screen->rms_residual_m, screen_voxels, params.max_residual_voxels) +
            gate_unit + " (on " + std::to_string(screen->source_points) + " points)";
        report->screened = true;
        return Status::Ok();
      }
      T_start = screen->T_target_source;
    }
  }
  auto icp = RefineIcp(a.features->IcpIndex(finest_resolution_m), b.grid->occupied_centres(),
                       T_start, params.icp);
  if (!icp.ok()) {
    times->alignment_s += SecondsSince(start);
    if (icp.status().code() != StatusCode::kFailedPrecondition) return icp.status();
    report->reason = icp.status().message();
    return Status::Ok();
  }
  report->T_a_b = icp->T_target_source;
  report->residual_m = icp->rms_residual_m;
  report->icp_iterations = icp->iterations;
  if (icp->converged && params.lattice_snap_deg > 0 &&
      a.grid->resolution() == b.grid->resolution()) {
    SnapToLattice(a, b, params, finest_resolution_m, report);
  }
  const OverlapScore overlap =
      ComputeOverlapScore(a.features->Overlap(), *b.grid, report->T_a_b, params.overlap_points);
  report->overlap_score = overlap.score;
  report->support_fraction = overlap.evaluated > 0 ? static_cast<double>(overlap.coinciding) /
                                                         static_cast<double>(overlap.evaluated)
                                                   : 0;
  times->alignment_s += SecondsSince(start);

  const double residual_voxels = report->residual_m / gate_voxel_m;
  // A refinement still moving when it ran out of iterations has not shown
  // where it ends: new_college 0.7 trial 3 was accepted at 0.98 voxels while
  // still 0.65 deg / 3 voxels off after 50 iterations, and converged to the
  // right transform (0.53 voxel) after 85.
  if (!icp->converged) {
    report->reason = "ICP did not converge in " + std::to_string(icp->iterations) +
                     " iterations (residual " + Fixed(residual_voxels, 2) + " voxels)" + gate_unit;
    return Status::Ok();
  }
  if (residual_voxels > params.max_residual_voxels) {
    report->reason =
        ResidualReason(report->residual_m, residual_voxels, params.max_residual_voxels) + gate_unit;
    return Status::Ok();
  }
  if (report->overlap_score < params.min_overlap_score) {
    report->reason = "overlap score " + Fixed(report->overlap_score, 2) + " below " +
                     Fixed(params.min_overlap_score, 2);
    return Status::Ok();
  }
  if (report->support_fraction < params.min_support_fraction) {
    report->reason = "support " + Fixed(report->support_fraction, 3) + " below " +
                     Fixed(params.min_support_fraction, 3) + " (B's voxels coinciding with A's)";
    return Status::Ok();
  }
  // Only now: a right merge reaches this once or twice, and maps that carry
  // no free space (built from points alone) have nothing to share.
  if (a.grid->has_free_space() && b.grid->has_free_space() && overlap.coinciding > 0) {
    const auto start_free = std::chrono::steady_clock::now();
    const SharedFree free =
        ComputeSharedFree(a.features->Overlap(), *b.grid, report->T_a_b, params.overlap_points);
    times->alignment_s += SecondsSince(start_free);
    // Both counts in B's voxels: the coinciding ones were counted every
    // `step`-th.
    report->shared_free_ratio = free.shared_voxels() / (static_cast<double>(overlap.coinciding) *
                                                        static_cast<double>(overlap.step));
    if (report->shared_free_ratio < params.min_shared_free_ratio) {
      report->reason = "shared free space " + Fixed(report->shared_free_ratio, 2) +
                       " voxels per coinciding voxel, below " +
                       Fixed(params.min_shared_free_ratio, 2) +
                       " (B's surfaces lie on A's, but the space in front of them that one map "
                       "saw as free the other did not see)";
      return Status::Ok();
    }
  }
  // Last: a right merge reaches this once or twice, and it costs six ICP
  // screens.
  if (params.max_restart_spread_voxels > 0) {
    const auto start_spread = std::chrono::steady_clock::now();
    auto spread_m = RestartSpread(a, b, params, report->T_a_b, finest_resolution_m, gate_voxel_m);
    times->alignment_s += SecondsSince(start_spread);
    if (!spread_m.ok()) return spread_m.status();
    report->restart_spread_voxels = *spread_m / gate_voxel_m;
    if (report->restart_spread_voxels > params.max_restart_spread_voxels) {
      report->reason = "ICP restarts turned by " + Fixed(params.restart_turn_deg, 1) +
                       " deg end up to " + Fixed(report->restart_spread_voxels, 2) +
                       " voxels apart at B's corners, above " +
                       Fixed(params.max_restart_spread_voxels, 2) + gate_unit +
                       " (the overlap does not fix the alignment)";
      return Status::Ok();
    }
  }
  report->accepted = true;
  return Status::Ok();
}

namespace {

// One corner solution: the maximum clique (without `excluded` pairs),
// Umeyama, ICP, the acceptance gates. `correspondences` gets the clique used.
StatusOr<PairReport> TrySolution(const PairSide& a, const PairSide& b, const CornerSet& corners_a,
                                 const CornerSet& corners_b, const MergeParams& params,
                                 const CornerMatcher& matcher,
                                 const std::vector<std::pair<int, int>>& excluded,
                                 double max_search_seconds, double finest_resolution_m,
                                 StageTimes* times, std::vector<CornerPair>* correspondences) {
  PairReport report;
  report.id_a = a.id;
  report.id_b = b.id;

  // B.4: corners, the maximum clique, Umeyama; ties go to the transform that
  // makes the most occupied voxels coincide (the paper, section IV.C).
  auto start = std::chrono::steady_clock::now();
  const TransformScore tie_score = [&](const Eigen::Isometry3d& T_a_b) {
    return static_cast<double>(
        ComputeOverlapScore(a.features->Overlap(), *b.grid, T_a_b, params.tie_break_points)
            .coinciding);
  };
  auto match = matcher.Match(excluded, max_search_seconds, tie_score);
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
    report.matched_a_b.emplace_back(corners_a[static_cast<std::size_t>(p.a)].position,
                                    corners_b[static_cast<std::size_t>(p.b)].position);
  }
  report.T_a_b = match->T_a_b;

  MAPD_RETURN_IF_ERROR(
      RefineAndGate(a, b, params, match->T_a_b, finest_resolution_m, times, &report));
  return report;
}

// Corner matching's tolerance stages: `matching`'s, then looser_tolerances.
std::vector<MatchTolerances> ToleranceStages(const MergeParams& params) {
  std::vector<MatchTolerances> stages = {{params.matching.signature_tolerance_rad * 180.0 / M_PI,
                                          params.matching.normal_tolerance_rad * 180.0 / M_PI}};
  stages.insert(stages.end(), params.looser_tolerances.begin(), params.looser_tolerances.end());
  return stages;
}

// What the corner generator did for one pair.
struct CornerRun {
  std::vector<TriedHypothesis> tried;  // solutions that reached ICP, in order
  PairReport first;                    // the first solution (its reason heads a refusal)
  int solutions = 0;                   // clique searches run
};

// B.4: corner matching's tolerance stages [stage_begin, stage_end) (the
// strict `matching` tolerances, then looser_tolerances), appended to `run`:
// up to max_match_attempts solutions per stage, each one's pairs excluded
// from the next search; after an accepted solution (or when
// `accepted_before`), uniqueness_corner_attempts more look for a distinct
// second one. Stops when `deadline_s` (seconds since `start`) has passed.
Status RunCornerStages(const PairSide& a, const PairSide& b, const MergeParams& params,
                       double finest_resolution_m, std::size_t stage_begin, std::size_t stage_end,
                       bool accepted_before, std::chrono::steady_clock::time_point start,
                       double deadline_s, StageTimes* times, CornerRun* run) {
  if (run->solutions == 0) {
    run->first.id_a = a.id;
    run->first.id_b = b.id;
  }
  auto corners_a = a.features->Corners(times);
  if (!corners_a.ok()) return corners_a.status();
  auto corners_b = b.features->Corners(times);
  if (!corners_b.ok()) return corners_b.status();
  const CornerSet& set_a = **corners_a;
  const CornerSet& set_b = **corners_b;
  const std::vector<MatchTolerances> stages = ToleranceStages(params);
  const int min_corners = params.min_matched_corners;
  if (static_cast<int>(std::min(set_a.size(), set_b.size())) < min_corners) {
    run->first.reason = "only " + std::to_string(std::min(set_a.size(), set_b.size())) +
                        " corners found in submap " +
                        std::to_string(set_a.size() < set_b.size() ? a.id : b.id) + ", need " +
                        std::to_string(min_corners);
    return Status::Ok();
  }
  bool accepted = accepted_before;
  int extra_left = params.uniqueness_corner_attempts;
  for (std::size_t stage = stage_begin; stage < std::min(stage_end, stages.size()); ++stage) {
    CornerMatchingParams matching = params.matching;
    matching.consistency_distance_m = params.consistency_distance_voxels * finest_resolution_m;
    matching.signature_tolerance_rad = stages[stage].signature_deg * M_PI / 180.0;
    matching.normal_tolerance_rad = stages[stage].normal_deg * M_PI / 180.0;
    // Candidate pairs and the consistency graph once per stage; each attempt
    // searches it without the pairs of the solutions before.
    std::optional<CornerMatcher> matcher;
    std::vector<std::pair<int, int>> excluded = params.matching.excluded_pairs;
    for (int attempt = 0; attempt < params.max_match_attempts; ++attempt) {
      const double left = deadline_s - SecondsSince(start);
      if ((run->solutions > 0 && left <= 0) || (accepted && extra_left-- <= 0)) break;
      if (matching.max_search_seconds <= 0 || matching.max_search_seconds > left) {
        matching.max_search_seconds = std::max(left, 1e-3);
      }
      if (!matcher.has_value()) {
        const auto built = std::chrono::steady_clock::now();
        auto created = CornerMatcher::Create(set_a, set_b, matching);
        times->matching_s += SecondsSince(built);
        if (!created.ok()) return created.status();
        matcher.emplace(std::move(created).value());
      }
      std::vector<CornerPair> used;
      StatusOr<PairReport> report =
          TrySolution(a, b, set_a, set_b, params, *matcher, excluded, matching.max_search_seconds,
                      finest_resolution_m, times, &used);
      ++run->solutions;
      if (!report.ok()) return report.status();
      if (run->solutions == 1) run->first = *report;
      if (!used.empty()) {
        report->by_corners = true;
        run->tried.push_back({"corner solution " + std::to_string(run->solutions), *report});
        accepted = accepted || report->accepted;
      }
      // Too few corners ends the stage; a solution's pairs are excluded and
      // the search rerun (for a better one, or a distinct second one).
      if (used.empty()) break;
      for (const CornerPair& p : used) excluded.emplace_back(p.a, p.b);
    }
    if (accepted && extra_left < 0) break;
  }
  return Status::Ok();
}

bool AnyAccepted(const std::vector<TriedHypothesis>& tried) {
  for (const TriedHypothesis& h : tried) {
    if (h.report.accepted) return true;
  }
  return false;
}

std::string DescribeCorners(const CornerRun& run, bool ran) {
  if (!ran) return "corner matching: not run";
  return "corner matching: " + run.first.reason + " (" + std::to_string(run.solutions) +
         " corner solution" + (run.solutions == 1 ? "" : "s") + " tried, " +
         std::to_string(run.tried.size()) + " reached ICP)";
}

}  // namespace

namespace {

std::vector<HypothesisReport> Summaries(const std::vector<TriedHypothesis>& tried) {
  std::vector<HypothesisReport> out;
  out.reserve(tried.size());
  for (const TriedHypothesis& h : tried) {
    const PairReport& r = h.report;
    out.push_back({h.label, r.T_a_b, r.screened, r.residual_m, r.overlap_score, r.support_fraction,
                   r.accepted, r.reason});
  }
  return out;
}

}  // namespace

StatusOr<PairReport> AlignPair(const PairSide& a, const PairSide& b, const MergeParams& params,
                               double finest_resolution_m, double seconds_left, StageTimes* times) {
  const auto start = std::chrono::steady_clock::now();
  const CorrelationParams& cp = params.correlation;
  const std::size_t num_stages = ToleranceStages(params).size();
  // Corner stages before the correlation generator (all of them without it).
  const std::size_t stages_before =
      cp.enabled
          ? std::min<std::size_t>(static_cast<std::size_t>(cp.after_corner_stages), num_stages)
          : num_stages;
  const auto time_left = [&] { return seconds_left - SecondsSince(start) > 0; };

  CornerRun corners;
  if (stages_before > 0) {
    MAPD_RETURN_IF_ERROR(RunCornerStages(a, b, params, finest_resolution_m, 0, stages_before, false,
                                         start, seconds_left, times, &corners));
  }
  // B.9: when those stages accepted nothing, or to check what they accepted.
  CorrelationRun correlation;
  bool correlation_ran = false;
  const bool corner_accepted = AnyAccepted(corners.tried);
  if (cp.enabled && (!corner_accepted || cp.check_corner_solutions) &&
      (stages_before == 0 || time_left())) {
    std::vector<Eigen::Isometry3d> accepted;
    for (const TriedHypothesis& h : corners.tried) {
      if (h.report.accepted) accepted.push_back(h.report.T_a_b);
    }
    auto run = RunCorrelation(a, b, params, finest_resolution_m, accepted, times);
    if (!run.ok()) return run.status();
    correlation = std::move(run).value();
    correlation_ran = true;
  }
  // The remaining corner stages, when nothing was accepted yet; after a
  // search that refused, the strict stage only (when the generator went
  // first), unless looser_stages_after_refusal.
  const bool correlation_searched = correlation_ran && correlation.not_run.empty();
  const std::size_t stages_end = correlation_searched && !cp.looser_stages_after_refusal
                                     ? std::max<std::size_t>(stages_before, 1)
                                     : num_stages;
  if (stages_before < stages_end && !corner_accepted && !AnyAccepted(correlation.tried) &&
      (corners.solutions == 0 || time_left())) {
    MAPD_RETURN_IF_ERROR(RunCornerStages(a, b, params, finest_resolution_m, stages_before,
                                         stages_end, false, start, seconds_left, times, &corners));
  }
  const bool corners_ran = corners.solutions > 0 || !corners.first.reason.empty();

  // Every hypothesis that reached ICP: corner solutions, then correlation peaks.
  std::vector<TriedHypothesis> tried = corners.tried;
  const std::size_t corner_hypotheses = tried.size();
  for (TriedHypothesis& h : correlation.tried) tried.push_back(std::move(h));
  // The best accepted hypothesis: the most support (most voxels coincide).
  int accepted_index = -1;
  for (std::size_t i = 0; i < tried.size(); ++i) {
    if (!tried[i].report.accepted) continue;
    if (accepted_index < 0 ||
        tried[i].report.support_fraction >
            tried[static_cast<std::size_t>(accepted_index)].report.support_fraction) {
      accepted_index = static_cast<int>(i);
    }
  }

  // The uniqueness gate, and the margin to the best distinct hypothesis.
  const Eigen::Vector3d& centroid_b = b.features->OccupiedCentroid();
  const auto distinct = [&](const PairReport& x, const PairReport& y) {
    return DistinctTransforms(x.T_a_b, y.T_a_b, centroid_b, params, finest_resolution_m);
  };
  if (accepted_index >= 0) {
    // The answer's 180 deg twin (b turned about its vertical through its
    // centroid) is always refined, unless a hypothesis already ended there. A
    // room symmetric under that turn passes every gate at both; which of the
    // twin yaw's peaks the generator refines hangs on last-bit ties between
    // them, and in a generated empty room it missed the twin in 3 of 24
    // poses, which then merged (docs/voxel-merge.md).
    const TriedHypothesis& answer = tried[static_cast<std::size_t>(accepted_index)];
    const StatusOr<GravityFrame>& frame_b = b.features->Gravity(times);
    const Eigen::Vector3d up = frame_b.ok() ? frame_b->up : Eigen::Vector3d::UnitZ();
    const Eigen::Isometry3d turn = Eigen::Translation3d(centroid_b) *
                                   Eigen::AngleAxisd(M_PI, up.normalized()) *
                                   Eigen::Translation3d(-centroid_b);
    TriedHypothesis twin;
    twin.label = "the 180 deg turn of " + answer.label;
    twin.report.id_a = a.id;
    twin.report.id_b = b.id;
    twin.report.T_a_b = answer.report.T_a_b * turn;
    const bool reached = std::any_of(tried.begin(), tried.end(), [&](const TriedHypothesis& h) {
      return h.report.residual_m > 0 && !distinct(h.report, twin.report);
    });
    if (!reached) {
      MAPD_RETURN_IF_ERROR(
          RefineAndGate(a, b, params, twin.report.T_a_b, finest_resolution_m, times, &twin.report));
      tried.push_back(std::move(twin));  // `answer` is not used past here
    }

    const TriedHypothesis& best = tried[static_cast<std::size_t>(accepted_index)];
    PairReport report = best.report;
    report.source = best.label;
    report.hypotheses = Summaries(tried);
    report.hypotheses_tried = static_cast<int>(tried.size());
    report.corner_solutions_tried = corners.solutions;
    report.correlation_hypotheses = correlation.generated;
    const TriedHypothesis* second = nullptr;
    const TriedHypothesis* rival = nullptr;
    for (const TriedHypothesis& h : tried) {
      if (&h == &best || h.report.residual_m <= 0 || !distinct(h.report, best.report)) continue;
      if (h.report.accepted && rival == nullptr && IsRival(best.report, h.report, params)) {
        rival = &h;
      }
      if (second == nullptr || h.report.residual_m < second->report.residual_m) second = &h;
    }
    if (second != nullptr) {
      report.second_residual_m = second->report.residual_m;
      report.second_overlap_score = second->report.overlap_score;
      report.second_support_fraction = second->report.support_fraction;
    }
    if (rival != nullptr) {
      report.accepted = false;
      report.reason = "ambiguous: two distinct alignments pass every gate: " +
                      DescribeHypothesis(best, finest_resolution_m) + " and " +
                      DescribeHypothesis(*rival, finest_resolution_m);
    }
    return report;
  }

  // Refused: what every stage found, in the order they ran.
  PairReport report = corners.first;
  report.hypotheses = Summaries(tried);
  report.hypotheses_tried = static_cast<int>(tried.size());
  report.corner_solutions_tried = corners.solutions;
  report.correlation_hypotheses = correlation.generated;
  std::string about_correlation;
  if (!cp.enabled) {
    about_correlation = "correlation: disabled";
  } else if (!correlation_ran) {
    about_correlation = "correlation: not run (time budget spent)";
  } else if (!correlation.not_run.empty()) {
    about_correlation = "correlation: not run (" + correlation.not_run + ")";
  } else {
    const TriedHypothesis* best = nullptr;
    for (std::size_t i = corner_hypotheses; i < tried.size(); ++i) {
      if (best == nullptr || (tried[i].report.residual_m > 0 &&
                              tried[i].report.residual_m < best->report.residual_m)) {
        best = &tried[i];
      }
    }
    about_correlation = "correlation: ";
    if (correlation.plan_view > 0) {
      about_correlation += std::to_string(correlation.plan_view) + " plan-view placements, ";
    }
    about_correlation += std::to_string(correlation.generated) + " hypotheses from " +
                         std::to_string(correlation.yaws) + " yaws";
    if (best != nullptr) {
      about_correlation += ", best " + DescribeHypothesis(*best, finest_resolution_m) +
                           " refused: " + best->report.reason;
      if (corners.first.matched_corners == 0) {
        report.T_a_b = best->report.T_a_b;
        report.residual_m = best->report.residual_m;
        report.screened = best->report.screened;
        report.overlap_score = best->report.overlap_score;
        report.icp_iterations = best->report.icp_iterations;
      }
    }
  }
  std::string about_corners = DescribeCorners(corners, corners_ran);
  if (!corners_ran) about_corners += " (time budget spent)";
  report.reason = stages_before == 0 ? about_correlation + "; " + about_corners
                                     : about_corners + "; " + about_correlation;
  return report;
}

}  // namespace mapd::voxel
