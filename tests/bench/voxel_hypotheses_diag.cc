// Diagnostic (not a test): for trials of voxel_merge_bench (same crops, same
// seeds), the first corner solutions (the maximum clique, then the next with
// the previous solutions' pairs excluded), each refined by ICP, with every
// figure an acceptance gate could use and the true errors; and, from the
// ground truth, how many corners of B have a partner in A within D, how many
// of those survive candidate selection, and the normal error of those pairs.
// This is how the merge's gates and looser matching stages were chosen
// (docs/voxel-merge.md, "Why the merges failed").
//
//   voxel_hypotheses_diag MAP.bt OVERLAP TRIALS [SOLUTIONS=4] [FIRST_TRIAL=0]
//
// Environment: DIAG_SIG_DEG, DIAG_NORMAL_DEG, DIAG_TOP_K, DIAG_USE_NORMALS
// override the matching tolerances, DIAG_ICP_ITERATIONS the ICP's; DIAG_NORMALS=1 prints every true
// pair.

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "bench/voxel_crops.h"
#include "voxel/corner_extraction.h"
#include "voxel/corner_matching.h"
#include "voxel/icp.h"
#include "voxel/merge.h"
#include "voxel/merge_overlap.h"
#include "voxel/voxel_grid.h"

using namespace mapd;
using namespace mapd::voxel;

// Of B's occupied voxels mapped into A's occupied bounding box, the share on or next to an occupied
// voxel of A.
static void Agreement(const VoxelGrid& a, const VoxelGrid& b, const Eigen::Isometry3d& T,
                      double* agree, std::size_t* coincide, std::size_t* inbox) {
  std::size_t in = 0, co = 0;
  for (const auto& c : b.occupied_centres()) {
    const VoxelKey k = a.PointToKey(T * c);
    if ((k.array() < a.min_key().array()).any() || (k.array() > a.max_key().array()).any())
      continue;
    ++in;
    bool hit = false;
    for (int dx = -1; dx <= 1 && !hit; ++dx)
      for (int dy = -1; dy <= 1 && !hit; ++dy)
        for (int dz = -1; dz <= 1 && !hit; ++dz) hit = a.IsOccupied(k + VoxelKey(dx, dy, dz));
    co += hit;
  }
  *agree = in ? double(co) / double(in) : 0.0;
  *coincide = co;
  *inbox = in;
}

int main(int argc, char** argv) {
  if (argc < 4) return 2;
  const double overlap = std::atof(argv[2]);
  const int trials = std::atoi(argv[3]);
  const int solutions = argc > 4 ? std::atoi(argv[4]) : 4;
  const int first = argc > 5 ? std::atoi(argv[5]) : 0;
  MergeParams params;
  if (const char* v = std::getenv("DIAG_SIG_DEG"))
    params.matching.signature_tolerance_rad = std::atof(v) * M_PI / 180;
  if (const char* v = std::getenv("DIAG_NORMAL_DEG"))
    params.matching.normal_tolerance_rad = std::atof(v) * M_PI / 180;
  if (const char* v = std::getenv("DIAG_ICP_ITERATIONS")) params.icp.max_iterations = std::atoi(v);
  if (const char* v = std::getenv("DIAG_TOP_K")) params.matching.top_k = std::atoi(v);
  if (const char* v = std::getenv("DIAG_USE_NORMALS"))
    params.matching.use_normals = std::atoi(v) != 0;
  const auto visit = [&](int t, const bench::BenchTrial& trial) {
    const bench::CropPair* pair = &trial.pair;
    const VoxelGrid& a = trial.a;
    const VoxelGrid& b = trial.b;
    const double res = a.resolution();
    auto ca = ExtractCorners(a, params.corners);
    auto cb = ExtractCorners(b, params.corners);
    std::printf("trial %d yaw %.0f corners %zu %zu\n", t, pair->yaw_deg, ca->corners.size(),
                cb->corners.size());
    CornerMatchingParams m = params.matching;
    m.consistency_distance_m = params.consistency_distance_voxels * res;
    {
      // Ground truth: B corners whose true image lies within D of an A corner.
      const double D = m.consistency_distance_m;
      int true_any = 0, true_2d = 0;
      std::vector<CornerPair> truth;
      for (int j = 0; j < int(cb->corners.size()); ++j) {
        const Eigen::Vector3d p = pair->T_a_b * cb->corners[j].position;
        double best = 1e9;
        int bi = -1;
        for (int i = 0; i < int(ca->corners.size()); ++i) {
          const double d = (ca->corners[i].position - p).norm();
          if (d < best) {
            best = d;
            bi = i;
          }
        }
        if (best < D) {
          ++true_any;
          truth.push_back({bi, j});
        }
        if (best < 2 * D) ++true_2d;
      }
      const auto cands = SelectCandidatePairs(ca->corners, cb->corners, m);
      int in_cands = 0;
      for (const auto& tp : truth) in_cands += std::binary_search(cands.begin(), cands.end(), tp);
      auto count_in = [&](int top_k, double sig_deg) {
        CornerMatchingParams q = m;
        q.top_k = top_k;
        q.signature_tolerance_rad = sig_deg * M_PI / 180.0;
        const auto c = SelectCandidatePairs(ca->corners, cb->corners, q);
        int n = 0;
        for (const auto& tp : truth) n += std::binary_search(c.begin(), c.end(), tp);
        return n;
      };
      // Normal error of the true pairs: B's normals rotated by the truth against A's (best of +-,
      // any order).
      std::vector<double> nerr;
      for (const auto& tp : truth) {
        double worst = 0;
        std::vector<double> e3;
        for (const auto& nb : cb->corners[tp.b].normals) {
          const Eigen::Vector3d r = pair->T_a_b.linear() * nb;
          double best = 1e9;
          for (const auto& na : ca->corners[tp.a].normals)
            best = std::min(best, std::acos(std::min(1.0, std::abs(r.dot(na)))));
          worst = std::max(worst, best);
          e3.push_back(best * 180 / M_PI);
        }
        std::sort(e3.begin(), e3.end());
        if (std::getenv("DIAG_NORMALS")) {
          std::printf(
              "    pair a%d b%d: normal errs %.1f %.1f %.1f  support %d/%d  pos err %.2f vox\n",
              tp.a, tp.b, e3[0], e3[1], e3[2], ca->corners[tp.a].support, cb->corners[tp.b].support,
              (ca->corners[tp.a].position - pair->T_a_b * cb->corners[tp.b].position).norm() / res);
        }
        nerr.push_back(worst * 180 / M_PI);
      }
      std::sort(nerr.begin(), nerr.end());
      std::printf("  filters: topk1e4 %d, +sig90 %d; normal err deg median %.1f p80 %.1f\n",
                  count_in(10000, 10), count_in(10000, 90),
                  nerr.empty() ? -1 : nerr[nerr.size() / 2],
                  nerr.empty() ? -1 : nerr[nerr.size() * 8 / 10]);
      std::printf(
          "  truth: %d B corners within D of an A corner (%d within 2D), %d of them among %zu "
          "candidates\n",
          true_any, true_2d, in_cands, cands.size());
    }
    const TransformScore tie = [&](const Eigen::Isometry3d& T) {
      return double(ComputeOverlapScore(a, b, T, params.tie_break_points).coinciding);
    };
    for (int s = 0; s < solutions; ++s) {
      auto match = MatchCorners(ca->corners, cb->corners, m, tie);
      if (!match.ok() || !match->transform_valid) {
        std::printf("  sol %d: none\n", s);
        break;
      }
      const double r0 = bench::RotationErrorDeg(match->T_a_b, pair->T_a_b);
      const double t0 =
          bench::TranslationErrorAt(match->T_a_b, pair->T_a_b, pair->centroid_b) / res;
      auto icp =
          RefineIcp(a.occupied_centres(), b.occupied_centres(), match->T_a_b, res, params.icp);
      if (!icp.ok()) {
        std::printf("  sol %d: m %d init %.1fdeg %.1fvox icp: %s\n", s, match->matched_count, r0,
                    t0, icp.status().message().c_str());
      } else {
        const Eigen::Isometry3d T = icp->T_target_source;
        const double r1 = bench::RotationErrorDeg(T, pair->T_a_b);
        const double t1 = bench::TranslationErrorAt(T, pair->T_a_b, pair->centroid_b) / res;
        const OverlapScore os = ComputeOverlapScore(a, b, T, params.overlap_points);
        double agree;
        std::size_t co, inbox;
        Agreement(a, b, T, &agree, &co, &inbox);
        std::printf(
            "  sol %d: m %2d rms_c %.2fvox init %6.1fdeg %6.1fvox -> %6.2fdeg %6.2fvox %s | res "
            "%.2fvox inl %d/%zu (%.2f) it %d ov %.3f agree %.3f co %zu/%zu cofrac %.3f\n",
            s, match->matched_count, match->rms_residual_m / res, r0, t0, r1, t1,
            (r1 < 2 && t1 < 2) ? "RIGHT" : "wrong", icp->rms_residual_m / res, icp->inliers,
            icp->source_points,
            double(icp->inliers) / double(std::max<std::size_t>(1, icp->source_points)),
            icp->iterations, os.score, agree, co, inbox, double(co) / double(b.num_occupied()));
      }
      for (const auto& p : match->correspondences) m.excluded_pairs.emplace_back(p.a, p.b);
    }
    m.excluded_pairs.clear();
    std::fflush(stdout);
  };
  return bench::ForEachBenchTrial(argv[1], overlap, first, trials, visit);
}
