// Diagnostic (not a test): for trials of voxel_merge_bench (same crops, same
// seeds), the correlation generator's inputs and outputs against the ground
// truth: each map's levelling error, the true yaw after levelling and the yaw
// candidates, the coarse cell, and where among the translation peaks (with
// more peaks kept than the merge keeps) the first one near the truth ranks.
//
//   voxel_correlation_diag MAP.bt OVERLAP TRIALS [FIRST_TRIAL=0] [PEAKS_PER_YAW=20]
//
// Environment: DIAG_WALL_UP_ROUNDS, DIAG_YAW_PEAKS (GravityParams),
// DIAG_MAX_CELLS, DIAG_CELL_VOXELS, DIAG_FREE_WEIGHT, DIAG_MIN_OVERLAP
// (CorrelationParams), DIAG_NO_REFINEMENT, DIAG_BAND_LOW, DIAG_BAND_HIGH (its
// yaw_refinement).

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "bench/voxel_crops.h"
#include "voxel/correlation_search.h"
#include "voxel/gravity_alignment.h"
#include "voxel/merge.h"
#include "voxel/voxel_grid.h"
#include "voxel/yaw_refinement.h"

using namespace mapd;
using namespace mapd::voxel;

static double Deg(double rad) { return rad * 180.0 / M_PI; }

int main(int argc, char** argv) {
  if (argc < 4) return 2;
  const double overlap = std::atof(argv[2]);
  const int trials = std::atoi(argv[3]);
  const int first = argc > 4 ? std::atoi(argv[4]) : 0;
  MergeParams params;
  if (const char* v = std::getenv("DIAG_YAW_PEAKS")) params.gravity.yaw_peaks = std::atoi(v);
  if (const char* v = std::getenv("DIAG_WALL_UP_ROUNDS")) {
    params.gravity.wall_up_rounds = std::atoi(v);
  }
  CorrelationParams cp = params.correlation;
  cp.peaks_per_yaw = argc > 5 ? std::atoi(argv[5]) : 20;
  cp.max_hypotheses = 1000;
  if (const char* v = std::getenv("DIAG_MAX_CELLS")) cp.max_cells = std::strtoull(v, nullptr, 10);
  if (const char* v = std::getenv("DIAG_CELL_VOXELS")) cp.cell_voxels = std::atof(v);
  if (const char* v = std::getenv("DIAG_FREE_WEIGHT")) cp.free_weight = std::atof(v);
  if (const char* v = std::getenv("DIAG_MIN_OVERLAP")) cp.min_overlap_fraction = std::atof(v);
  if (std::getenv("DIAG_NO_REFINEMENT") != nullptr) cp.yaw_refinement.enabled = false;
  if (const char* v = std::getenv("DIAG_BAND_LOW")) cp.yaw_refinement.band_low_m = std::atof(v);
  if (const char* v = std::getenv("DIAG_BAND_HIGH")) cp.yaw_refinement.band_high_m = std::atof(v);
  const auto visit = [&](int t, const bench::BenchTrial& trial) {
    const bench::CropPair* pair = &trial.pair;
    const VoxelGrid& a = trial.a;
    const VoxelGrid& b = trial.b;
    const double res = a.resolution();
    auto fa = EstimateGravityFrame(a, params.gravity);
    auto fb = EstimateGravityFrame(b, params.gravity);
    if (!fa.ok() || !fb.ok()) {
      std::printf("trial %d: gravity: %s\n", t,
                  (fa.ok() ? fb.status() : fa.status()).message().c_str());
      return;
    }
    // The truth after levelling: R_a R_true R_b^T should turn about +z only.
    const Eigen::Matrix3d M = fa->R_up * pair->T_a_b.linear() * fb->R_up.transpose();
    const double tilt = Deg(std::acos(std::min(1.0, (M * Eigen::Vector3d::UnitZ()).z())));
    const double yaw_true = std::atan2(M(1, 0), M(0, 0));
    const double up_a = Deg(std::acos(std::min(1.0, fa->up.dot(Eigen::Vector3d::UnitZ()))));
    std::printf(
        "trial %d: up a %.2f deg from map z (floors %d, walls %d), b walls %d; levelled truth "
        "tilt %.2f deg, yaw %.1f deg\n  yaws:",
        t, up_a, fa->floor_planes, fa->wall_planes, fb->wall_planes, tilt, Deg(yaw_true));
    const std::vector<double> candidates = YawCandidates(*fa, *fb, params.gravity);
    for (double y : candidates) {
      std::printf(" %.1f (err %.1f)", Deg(y), Deg(std::remainder(y - yaw_true, 2 * M_PI)));
    }
    YawRefinementStats refinement;
    auto refined =
        RefineYaws(a, fa->R_up, b, fb->R_up, candidates, res, cp.yaw_refinement, &refinement);
    if (!refined.ok()) {
      std::printf("\n  refinement: %s\n", refined.status().message().c_str());
      return;
    }
    const std::vector<double>& yaws = *refined;
    std::printf("\n  refined (%d yaws scored, %.2f m columns):", refinement.yaws_scored,
                refinement.pixel_m);
    for (double y : yaws) {
      std::printf(" %.1f (err %.1f)", Deg(y), Deg(std::remainder(y - yaw_true, 2 * M_PI)));
    }
    std::printf("\n  plan-view scores (at candidate / best in window):");
    for (std::size_t k = 0; k < refinement.window_scores.size(); ++k) {
      std::printf(" %.3f/%.3f", refinement.candidate_scores[k], refinement.window_scores[k]);
    }
    // Where the window's best plan-view shift puts B's centroid, horizontally,
    // against the truth (in a's levelled frame), and the height from the
    // columns' lowest voxels (PlanViewHeights) against the truth's: could the
    // plan view alone start ICP?
    std::printf(
        "\n  plan-view placements (window's best yaw: yaw err, horizontal err at B's centroid):");
    const Eigen::Vector3d truth = fa->R_up * (pair->T_a_b * pair->centroid_b);
    const std::vector<double> heights =
        PlanViewHeights(a, fa->R_up, b, fb->R_up, refinement.window_yaws,
                        refinement.window_shifts_m, refinement.pixel_m);
    for (std::size_t k = 0; k < refinement.window_yaws.size(); ++k) {
      const double y = refinement.window_yaws[k];
      const Eigen::Vector3d turned =
          Eigen::AngleAxisd(y, Eigen::Vector3d::UnitZ()) * (fb->R_up * pair->centroid_b);
      const Eigen::Vector2d placed = turned.head<2>() + refinement.window_shifts_m[k];
      std::printf(" %.1f deg / %.2f m / height %.2f m", Deg(std::remainder(y - yaw_true, 2 * M_PI)),
                  (placed - truth.head<2>()).norm(), turned.z() + heights[k] - truth.z());
    }
    std::printf("\n");
    if (std::getenv("DIAG_PLAN_ONLY") != nullptr) return;
    // With the true yaw too, to see whether the translation search finds the truth given it.
    std::vector<double> all = yaws;
    all.push_back(yaw_true);
    CorrelationStats stats;
    auto hyps = SearchTranslations(a, fa->R_up, b, fb->R_up, all, res, cp, &stats);
    if (!hyps.ok()) {
      std::printf("  search: %s\n", hyps.status().message().c_str());
      return;
    }
    Eigen::AlignedBox3d box;
    for (const Eigen::Vector3d& c : a.occupied_centres()) box.extend(c);
    const Eigen::Vector3d extent = box.sizes();
    std::printf(
        "  cell %.2f m, grid %zu cells, %zu peaks; A's occupied extent %.0f x %.0f x "
        "%.0f m\n",
        stats.cell_m, stats.grid_cells, hyps->size(), extent.x(), extent.y(), extent.z());
    int shown = 0;
    {
      // The true yaw alone, many peaks: the rank of the first one near the truth.
      CorrelationParams one = cp;
      one.peaks_per_yaw = 300;
      auto only = SearchTranslations(a, fa->R_up, b, fb->R_up, {yaw_true}, res, one, nullptr);
      int rank = -1;
      double best_score = 0, truth_score = 0;
      for (std::size_t i = 0; only.ok() && i < only->size(); ++i) {
        const CorrelationHypothesis& h = (*only)[i];
        if (i == 0) best_score = h.score;
        if (bench::TranslationErrorAt(h.T_a_b, pair->T_a_b, pair->centroid_b) < 2 * stats.cell_m) {
          rank = static_cast<int>(i) + 1;
          truth_score = h.score;
          break;
        }
      }
      std::printf("  true yaw alone: first peak near the truth ranks %d (score %.3f, best %.3f)\n",
                  rank, truth_score, best_score);
    }
    for (std::size_t i = 0; i < hyps->size(); ++i) {
      const CorrelationHypothesis& h = (*hyps)[i];
      const double r = bench::RotationErrorDeg(h.T_a_b, pair->T_a_b);
      const double e = bench::TranslationErrorAt(h.T_a_b, pair->T_a_b, pair->centroid_b);
      const bool near = r < 3 + tilt && e < 2 * stats.cell_m;
      if (i < 5 || near) {
        std::printf("  #%zu yaw %.1f score %.3f: rot err %.1f deg, trans err %.2f m%s\n", i + 1,
                    Deg(h.yaw_rad), h.score, r, e, near ? "  <- near truth" : "");
        if (near && ++shown >= 3) break;
      }
    }
    std::fflush(stdout);
  };
  return bench::ForEachBenchTrial(argv[1], overlap, first, trials, visit);
}
