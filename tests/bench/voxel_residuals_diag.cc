// Diagnostic (not a test): the residuals of right and wrong hypotheses
// (issue 42 item 2). For trials of voxel_merge_bench (same crops, same seeds),
// the pair is aligned as MergeSubmaps aligns it (AlignPair, default
// MergeParams), and every hypothesis that reached ICP is judged against the
// ground truth by the benchmark's measure (right: < 2 deg and < 2 voxels at
// B's centroid). Prints each hypothesis, then how their ICP residuals are
// distributed, right apart from wrong and the ICP screen's apart from full
// ICP's, and per pair the lowest residual of a right and of a wrong one: a
// gate belongs in the gap between them, if there is one.
//
//   voxel_residuals_diag MAP.bt OVERLAPS TRIALS [NEGATIVES=0] [THREADS=2] [FIRST_TRIAL=0]
//
// OVERLAPS: comma-separated, e.g. 0.1,0.2,0.3,0.5. NEGATIVES: pairs of
// disjoint crops (every hypothesis of theirs is wrong).

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

#include "bench/voxel_crops.h"
#include "voxel/merge.h"
#include "voxel/merge_pair.h"
#include "voxel/submap_features.h"
#include "voxel/voxel_grid.h"

namespace {

using mapd::voxel::HypothesisReport;

// Upper bounds (voxels) of the residual bins; the last bin is open.
constexpr double kBins[] = {0.5, 0.6, 0.7, 0.75, 0.9, 1.2, 1.5, 2.0, 3.0};
constexpr std::size_t kNumBins = sizeof(kBins) / sizeof(kBins[0]) + 1;

std::size_t BinOf(double voxels) {
  std::size_t i = 0;
  while (i < kNumBins - 1 && voxels > kBins[i]) ++i;
  return i;
}

std::string BinName(std::size_t i) {
  char buf[32];
  if (i == kNumBins - 1) {
    std::snprintf(buf, sizeof(buf), "> %.2f", kBins[i - 1]);
  } else {
    std::snprintf(buf, sizeof(buf), "%.2f - %.2f", i == 0 ? 0.0 : kBins[i - 1], kBins[i]);
  }
  return buf;
}

struct Counts {
  // [right][screened][bin]
  int bins[2][2][kNumBins] = {};
  int failed[2] = {};  // ICP failed (no residual), [right]
  int accepted[2] = {};
  int right_refused_at_residual = 0;  // right, full ICP, refused by the residual gate
};

// The overlaps, each in (0, 1); empty when one is not.
std::vector<double> ParseOverlaps(const std::string& s) {
  std::vector<double> out;
  std::stringstream in(s);
  std::string item;
  while (std::getline(in, item, ',')) {
    char* end = nullptr;
    const double v = std::strtod(item.c_str(), &end);
    if (end == item.c_str() || *end != '\0' || !(v > 0 && v < 1)) return {};
    out.push_back(v);
  }
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 4) {
    std::fprintf(stderr,
                 "usage: %s MAP.bt OVERLAPS TRIALS [NEGATIVES=0] [THREADS=2] [FIRST_TRIAL=0]\n",
                 argv[0]);
    return 2;
  }
  const std::vector<double> overlaps = ParseOverlaps(argv[2]);
  const int trials = std::atoi(argv[3]);
  const int negatives = argc > 4 ? std::atoi(argv[4]) : 0;
  if (overlaps.empty() || trials < 0 || negatives < 0) {
    std::fprintf(stderr,
                 "OVERLAPS must be numbers in (0, 1) separated by commas, TRIALS and "
                 "NEGATIVES counts >= 0\n");
    return 2;
  }
  mapd::voxel::MergeParams params;
  params.threads = argc > 5 ? std::atoi(argv[5]) : 2;
  const int first = argc > 6 ? std::atoi(argv[6]) : 0;
  if (const mapd::Status valid = params.Validate(); !valid.ok() || first < 0) {
    std::fprintf(stderr, "%s\n",
                 valid.ok() ? "FIRST_TRIAL must be >= 0" : valid.ToString().c_str());
    return 2;
  }
  params.max_seconds = 600;  // a hang guard only: the machine may be loaded
  Counts counts;
  std::printf(
      "| overlap | trial | lowest residual of a right hypothesis (voxels) | lowest of a "
      "wrong one | pair accepted | right |\n|---|---|---|---|---|---|\n");
  std::ostringstream detail;
  std::vector<std::pair<double, int>> runs;  // (overlap, trials); overlap 0: the negatives
  for (const double o : overlaps) runs.emplace_back(o, trials);
  if (negatives > 0) runs.emplace_back(0.0, negatives);
  for (const auto& [overlap, count] : runs) {
    const int rc = mapd::bench::ForEachBenchTrial(
        argv[1], overlap, first, count, [&](int t, const mapd::bench::BenchTrial& trial) {
          const double voxel_m = trial.a.resolution();
          mapd::voxel::SubmapFeatures fa(1, &trial.a, &params), fb(2, &trial.b, &params);
          mapd::voxel::StageTimes times;
          auto pair = mapd::voxel::AlignPair({1, &trial.a, &fa}, {2, &trial.b, &fb}, params,
                                             voxel_m, params.max_seconds, &times);
          if (!pair.ok()) {
            std::printf("| %.1f | %d | error: %s | | | |\n", overlap, t,
                        pair.status().ToString().c_str());
            return;
          }
          const bool negative = overlap <= 0;
          const auto right_of = [&](const Eigen::Isometry3d& T) {
            return !negative && mapd::bench::RotationErrorDeg(T, trial.pair.T_a_b) < 2.0 &&
                   mapd::bench::TranslationErrorAt(T, trial.pair.T_a_b, trial.pair.centroid_b) /
                           voxel_m <
                       2.0;
          };
          double best[2] = {std::numeric_limits<double>::infinity(),
                            std::numeric_limits<double>::infinity()};
          for (const HypothesisReport& h : pair->hypotheses) {
            const bool right = right_of(h.T_a_b);
            const double voxels = h.residual_m / voxel_m;
            const double rot =
                negative ? std::nan("") : mapd::bench::RotationErrorDeg(h.T_a_b, trial.pair.T_a_b);
            const double trans = negative ? std::nan("")
                                          : mapd::bench::TranslationErrorAt(
                                                h.T_a_b, trial.pair.T_a_b, trial.pair.centroid_b) /
                                                voxel_m;
            char line[512];
            std::snprintf(line, sizeof(line),
                          "%.1f #%d %-48s %s residual %.2f vox, support %.3f, overlap %.2f; "
                          "err %.2f deg %.2f vox: %s, %s\n",
                          overlap, t, h.label.c_str(), h.screened ? "screen" : "full  ", voxels,
                          h.support_fraction, h.overlap_score, rot, trans,
                          right ? "RIGHT" : "wrong",
                          h.accepted ? "accepted" : h.reason.substr(0, 90).c_str());
            detail << line;
            if (h.residual_m <= 0) {
              ++counts.failed[right];
              continue;
            }
            ++counts.bins[right][h.screened][BinOf(voxels)];
            counts.accepted[right] += h.accepted ? 1 : 0;
            if (right && !h.screened && !h.accepted && h.reason.rfind("residual", 0) == 0) {
              ++counts.right_refused_at_residual;
            }
            if (!h.screened) best[right] = std::min(best[right], voxels);
          }
          const bool pair_right = pair->accepted && right_of(pair->T_a_b);
          std::printf("| %s | %d | %.2f | %.2f | %s | %s |\n",
                      negative ? "disjoint" : std::to_string(overlap).substr(0, 3).c_str(), t,
                      best[1], best[0], pair->accepted ? "yes" : "no",
                      pair->accepted ? (pair_right ? "yes" : "NO") : "-");
          std::fflush(stdout);
        });
    if (rc != 0) return rc;
  }
  std::printf(
      "\nResiduals (voxels) of every hypothesis that reached ICP, by bin: right / wrong, "
      "after full ICP and at the ICP screen (%d of B's voxels):\n\n"
      "| residual (voxels) | right, full ICP | wrong, full ICP | right, screen | wrong, "
      "screen |\n|---|---|---|---|---|\n",
      static_cast<int>(params.icp_screen_points));
  for (std::size_t i = 0; i < kNumBins; ++i) {
    std::printf("| %s | %d | %d | %d | %d |\n", BinName(i).c_str(), counts.bins[1][0][i],
                counts.bins[0][0][i], counts.bins[1][1][i], counts.bins[0][1][i]);
  }
  std::printf(
      "\nICP failed (no residual): %d right, %d wrong. Accepted by their own gates: %d "
      "right, %d wrong. Right after full ICP but refused by the residual gate (%.2f "
      "voxels): %d.\n\nEvery hypothesis:\n\n%s",
      counts.failed[1], counts.failed[0], counts.accepted[1], counts.accepted[0],
      params.max_residual_voxels, counts.right_refused_at_residual, detail.str().c_str());
  return 0;
}
