#include "voxel/merge_hypotheses.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <utility>

#include "common/clock.h"
#include "voxel/correlation_search.h"
#include "voxel/gravity_alignment.h"
#include "voxel/submap_features.h"
#include "voxel/yaw_refinement.h"

namespace mapd::voxel {
namespace {

std::string Format(const char* format, double x, double y, double z) {
  char buffer[128];
  std::snprintf(buffer, sizeof(buffer), format, x, y, z);
  return buffer;
}

}  // namespace

bool DistinctTransforms(const Eigen::Isometry3d& x, const Eigen::Isometry3d& y,
                        const Eigen::Vector3d& centroid_b, const MergeParams& params,
                        double finest_resolution_m) {
  const double angle =
      Eigen::AngleAxisd(x.linear().transpose() * y.linear()).angle() * 180.0 / M_PI;
  const double offset = (x * centroid_b - y * centroid_b).norm() / finest_resolution_m;
  return angle > params.distinct_rotation_deg || offset > params.distinct_translation_voxels;
}

bool IsRival(const PairReport& best, const PairReport& h, const MergeParams& params) {
  return h.support_fraction >= params.ambiguous_support_ratio * best.support_fraction ||
         h.overlap_score >= best.overlap_score + params.ambiguous_overlap_margin;
}

std::string DescribeHypothesis(const TriedHypothesis& h, double finest_resolution_m) {
  const PairReport& r = h.report;
  const double angle = Eigen::AngleAxisd(r.T_a_b.linear()).angle() * 180.0 / M_PI;
  const Eigen::Vector3d t = r.T_a_b.translation();
  return h.label + " (rotation " + Format("%.1f", angle, 0, 0) + " deg, translation " +
         Format("(%.2f, %.2f, %.2f)", t.x(), t.y(), t.z()) + " m, residual " +
         Format("%.2f", r.residual_m / finest_resolution_m, 0, 0) + " voxels, overlap " +
         Format("%.2f", r.overlap_score, 0, 0) + ", support " +
         Format("%.3f", r.support_fraction, 0, 0) + ")";
}

StatusOr<CorrelationRun> RunCorrelation(const PairSide& a, const PairSide& b,
                                        const MergeParams& params, double finest_resolution_m,
                                        const std::vector<Eigen::Isometry3d>& accepted,
                                        StageTimes* times) {
  CorrelationRun run;
  const StatusOr<GravityFrame>& frame_a = a.features->Gravity(times);
  const StatusOr<GravityFrame>& frame_b = b.features->Gravity(times);
  if (!frame_a.ok() || !frame_b.ok()) {
    const Status& bad = frame_a.ok() ? frame_b.status() : frame_a.status();
    if (bad.code() != StatusCode::kFailedPrecondition) return bad;
    run.not_run = "submap " + std::to_string(frame_a.ok() ? b.id : a.id) + ": " + bad.message();
    return run;
  }
  const auto start = std::chrono::steady_clock::now();
  const std::vector<double> candidates = YawCandidates(*frame_a, *frame_b, params.gravity);
  YawRefinementStats refinement;
  auto yaws =
      RefineYaws(*a.grid, frame_a->R_up, *b.grid, frame_b->R_up, candidates, finest_resolution_m,
                 params.correlation.yaw_refinement, &refinement, params.threads);
  if (!yaws.ok()) {
    times->correlation_s += SecondsSince(start);
    return yaws.status();
  }
  const Eigen::Vector3d& centroid_b = b.features->OccupiedCentroid();
  std::vector<Eigen::Isometry3d> known = accepted;
  // Whether a start lies where an accepted answer already is.
  const auto agrees = [&](const Eigen::Isometry3d& T) {
    return std::any_of(known.begin(), known.end(), [&](const Eigen::Isometry3d& answer) {
      return !DistinctTransforms(answer, T, centroid_b, params, finest_resolution_m);
    });
  };
  // Refines one start (ICP screen, ICP, every gate) into run.tried; an
  // accepted one becomes known.
  const auto refine = [&](std::string label, const Eigen::Isometry3d& T) -> Status {
    TriedHypothesis tried;
    tried.label = std::move(label);
    tried.report.id_a = a.id;
    tried.report.id_b = b.id;
    MAPD_RETURN_IF_ERROR(RefineAndGate(a, b, params, T, finest_resolution_m, times, &tried.report));
    if (tried.report.accepted) known.push_back(tried.report.T_a_b);
    run.tried.push_back(std::move(tried));
    return Status::Ok();
  };

  // Outdoors, the plan view first (CorrelationParams::plan_view_first_min_cells).
  std::vector<double> search_yaws = *yaws;
  bool plan_view_ran = false, plan_view_placed = false;
  if (CorrelationGridCells(*a.grid, frame_a->R_up, *b.grid, frame_b->R_up, *yaws,
                           finest_resolution_m,
                           params.correlation) > params.correlation.plan_view_first_min_cells) {
    const std::vector<double> heights =
        PlanViewHeights(*a.grid, frame_a->R_up, *b.grid, frame_b->R_up, refinement.window_yaws,
                        refinement.window_shifts_m, refinement.pixel_m, params.threads);
    std::vector<std::size_t> order(heights.size());
    for (std::size_t k = 0; k < order.size(); ++k) order[k] = k;
    std::stable_sort(order.begin(), order.end(), [&](std::size_t x, std::size_t y) {
      return refinement.window_scores[x] > refinement.window_scores[y];
    });
    times->correlation_s += SecondsSince(start);  // RefineAndGate counts its own
    plan_view_ran = true;
    double best_support = -1;  // of the accepted placements
    for (const std::size_t k : order) {
      if (!std::isfinite(heights[k])) continue;  // no structure, or no shared column
      const double yaw = refinement.window_yaws[k];
      const Eigen::Matrix3d R =
          Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix() * frame_b->R_up;
      const Eigen::Vector3d t(refinement.window_shifts_m[k].x(), refinement.window_shifts_m[k].y(),
                              heights[k]);
      Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
      T.linear() = frame_a->R_up.transpose() * R;  // x_a = R_a^T (R x_b + t)
      T.translation() = frame_a->R_up.transpose() * t;
      if (agrees(T)) {
        ++run.agreeing;
        continue;
      }
      ++run.plan_view;
      MAPD_RETURN_IF_ERROR(
          refine("plan view yaw " + Format("%.1f", yaw * 180.0 / M_PI, 0, 0) + " deg", T));
      const PairReport& report = run.tried.back().report;
      if (report.accepted && report.support_fraction > best_support) {
        best_support = report.support_fraction;
        search_yaws = {yaw, std::remainder(yaw + M_PI, 2 * M_PI)};
        plan_view_placed = true;
      }
    }
  }

  const auto search_start = std::chrono::steady_clock::now();
  run.yaws = static_cast<int>(search_yaws.size());
  CorrelationParams search = params.correlation;
  search.max_hypotheses = 1000;  // every peak (the most Validate allows); capped below
  auto all = SearchTranslations(*a.grid, frame_a->R_up, *b.grid, frame_b->R_up, search_yaws,
                                finest_resolution_m, search, nullptr, params.threads);
  times->correlation_s += SecondsSince(plan_view_ran ? search_start : start);
  if (!all.ok()) return all.status();
  // The candidates' best max_hypotheses first, then the best peak of each
  // yaw the refinement added. The added yaws are extras: ranked with the
  // others on one score their peaks pushed a right, lower peak of a
  // candidate out of the first 12 (fr_078_tidyup at 10 % overlap: 5/6 -> 2/6
  // right), and with all their peaks kept a lower one slid the generated
  // corridor along itself past every gate. Given a right yaw the true shift
  // was the best peak in 5 of 6 campus pairs (docs/voxel-merge.md). After a
  // plan-view placement, every peak of its two yaws.
  std::vector<CorrelationHypothesis> hypotheses, added;
  for (const CorrelationHypothesis& h : *all) {
    const bool from_candidate = plan_view_placed || std::find(candidates.begin(), candidates.end(),
                                                              h.yaw_rad) != candidates.end();
    if (!from_candidate) {
      const bool first_of_yaw =
          std::none_of(added.begin(), added.end(),
                       [&](const CorrelationHypothesis& x) { return x.yaw_rad == h.yaw_rad; });
      if (first_of_yaw) added.push_back(h);
    } else if (static_cast<int>(hypotheses.size()) < params.correlation.max_hypotheses) {
      hypotheses.push_back(h);
    }
  }
  hypotheses.insert(hypotheses.end(), added.begin(), added.end());
  run.generated = static_cast<int>(hypotheses.size());

  // Hypotheses are refined best first. Once an answer is accepted (here or
  // by corner matching) only the best distinct peak of each yaw is that was
  // not refined before (peaks refused before the answer do not count): enough
  // for the uniqueness gate to see the other yaws (a symmetric building's
  // twin is another yaw) and a second place at the answer's own yaw (a slide
  // along a corridor), while every further peak would cost an ICP screen.
  std::vector<double> yaws_checked;  // a peak refined while an answer was known
  for (std::size_t i = 0; i < hypotheses.size(); ++i) {
    const CorrelationHypothesis& h = hypotheses[i];
    if (agrees(h.T_a_b)) {
      ++run.agreeing;
      continue;
    }
    if (!known.empty()) {
      if (std::find(yaws_checked.begin(), yaws_checked.end(), h.yaw_rad) != yaws_checked.end()) {
        continue;
      }
      yaws_checked.push_back(h.yaw_rad);
    }
    MAPD_RETURN_IF_ERROR(refine("correlation yaw " +
                                    Format("%.1f", h.yaw_rad * 180.0 / M_PI, 0, 0) + " deg, peak " +
                                    std::to_string(i + 1),
                                h.T_a_b));
  }
  return run;
}

}  // namespace mapd::voxel
