// The paper's comparison (feature-fusion paper, Li et al. 2023, section 4,
// Tables 1-3) on the
// synthetic urban scenario (sim/city_scenario.h), for the three strategies side by
// side, with and without pose noise; and the speed targets of the fusion issue
// (item 8). A benchmark, not a test: run it by hand, figures go to docs/.
//
//   fusion_bench [--repeats N] [--seed S] [--svg-dir DIR] [--wall-gap M]
//                [--occluded-gap M] [--occluded-ratio R] [--free-min-count N]   the comparison
//   fusion_bench --million [--blocks-x X --blocks-y Y] [--bounded]   1M-feature world, streaming
#include <sys/resource.h>
#include <time.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <iterator>
#include <memory>
#include <string>
#include <vector>

#include "eval/fuser_registry.h"
#include "eval/metrics.h"
#include "eval/svg.h"
#include "sim/city_scenario.h"

namespace {

using mapd::fusion::CornerMode;
using mapd::fusion::CornerPairing;
using mapd::fusion::FusedFeature;
using mapd::fusion::Fuser;
using mapd::fusion::FuserOptions;
using mapd::geometry::Segment2;
using mapd::geometry::Vec2;
namespace sc = mapd::fusion::scenario;

double Seconds(std::chrono::steady_clock::time_point since) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - since).count();
}

// CPU time of this thread: on a shared, oversubscribed machine the wall clock
// also counts the time other processes ran; this does not.
double CpuNow() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

double Median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

long PeakRssMiB() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return usage.ru_maxrss / 1024;  // ru_maxrss is in KiB on Linux
}

struct Method {
  std::string label;
  std::string name;
  FuserOptions options;
};

// --wall-gap M: the consolidation gap of the proposed method's rows (< 0: the default).
double g_wall_gap_m = -1.0;
// --occluded-gap M / --occluded-ratio R / --free-min-count N: free-space evidence
// (FusionParams::wall_occluded_gap_m, wall_occluded_gap_ratio, wall_free_min_count) for
// every three_criteria row (<= 0: the default).
double g_occluded_gap_m = -1.0;
double g_occluded_ratio = -1.0;
int g_free_min_count = -1;

std::vector<Method> Methods() {
  FuserOptions base;  // defaults; baselines post-process like the proposed method
  if (g_wall_gap_m >= 0.0) base.three_criteria.wall_gap_m = g_wall_gap_m;
  if (g_occluded_gap_m >= 0.0) base.three_criteria.wall_occluded_gap_m = g_occluded_gap_m;
  if (g_occluded_ratio > 0.0) base.three_criteria.wall_occluded_gap_ratio = g_occluded_ratio;
  if (g_free_min_count > 0) base.three_criteria.wall_free_min_count = g_free_min_count;
  base.mean_shift.post.snap_m = base.three_criteria.snap_m;
  base.mean_shift.post.corner_mode = base.three_criteria.corner_mode;
  base.density.post.snap_m = base.three_criteria.snap_m;
  base.density.post.corner_mode = base.three_criteria.corner_mode;
  Method midpoint{"three_criteria (midpoint corners)", "three_criteria", base};
  midpoint.options.three_criteria.corner_mode = CornerMode::kMidpoint;
  Method paper{"three_criteria (no consolidation: the paper's output)", "three_criteria", base};
  paper.options.three_criteria.consolidate = false;
  // Consolidation without free-space evidence (the occluded-gap join off).
  Method blind{"three_criteria (no free-space evidence)", "three_criteria", base};
  blind.options.three_criteria.wall_occluded_gap_m = 0.0;
  // The two corner pairings (docs/fusion.md, "Corner pairing"), the rest as the default.
  Method mutual{"three_criteria (mutual nearest pairing)", "three_criteria", base};
  mutual.options.three_criteria.corner_pairing = CornerPairing::kMutualNearest;
  Method greedy{"three_criteria (greedy pairing)", "three_criteria", base};
  greedy.options.three_criteria.corner_pairing = CornerPairing::kGreedy;
  return {{"mean_shift (competing 1)", "mean_shift", base},
          {"density (competing 2)", "density", base},
          {"three_criteria (proposed, intersection)", "three_criteria", base},
          paper,
          blind,
          midpoint,
          mutual,
          greedy};
}

using FusedFeatures = std::vector<FusedFeature>;

struct Run {
  std::vector<FusedFeature> fused;
  double seconds = 0.0;      // wall clock
  double cpu_seconds = 0.0;  // this thread's CPU time
};

Run Fuse(const Method& m, const std::vector<sc::Scan>& scans) {
  auto fuser = mapd::fusion::MakeFuser(m.name, m.options);
  if (!fuser.ok()) {
    std::fprintf(stderr, "%s\n", fuser.status().ToString().c_str());
    std::exit(1);
  }
  const auto start = std::chrono::steady_clock::now();
  const double cpu_start = CpuNow();
  for (const sc::Scan& s : scans) {
    // The sensor sits at the vehicle's (estimated) origin.
    const mapd::Status st =
        (*fuser)->AddFrom(s.observation, s.robot, s.estimated_pose.t, s.features, nullptr);
    if (!st.ok()) {
      std::fprintf(stderr, "%s\n", st.ToString().c_str());
      std::exit(1);
    }
  }
  Run run;
  run.fused = (*fuser)->Published();
  run.seconds = Seconds(start);
  run.cpu_seconds = CpuNow() - cpu_start;
  return run;
}

int Compare(int repeats, uint64_t seed, const std::string& svg_dir) {
  for (int noisy = 0; noisy < 2; ++noisy) {
    sc::ScenarioParams params;
    params.seed = seed;
    if (noisy) {
      params.pose_sigma_xy_m = 0.05;
      params.pose_sigma_yaw_rad = 0.2 * 3.14159265358979323846 / 180.0;
    }
    auto start = std::chrono::steady_clock::now();
    const sc::World world = sc::GenerateWorld(params);
    const sc::ScanSimulator sim(params, world);
    std::vector<sc::Scan> scans;
    size_t raw = 0;
    for (size_t k = 0; k < sim.size(); ++k) {
      scans.push_back(sim.Simulate(k));
      raw += scans.back().features.size();
    }
    std::printf("\n### %s (seed %llu)\n\n",
                noisy ? "With pose noise (5 cm, 0.2 deg per scan)" : "Without pose noise",
                static_cast<unsigned long long>(seed));
    std::printf(
        "World: %zu buildings (%zu close pairs), %zu walls, %zu trivial segments; "
        "%zu scans, %zu raw line features; generated in %.2f s.\n\n",
        world.buildings.size(), world.close_pairs.size(), world.wall_count,
        world.structures.size() - world.wall_count, scans.size(), raw, Seconds(start));
    std::printf(
        "| method | fused (T1) | walls seen / matched | features per matched wall | "
        "on fences | spurious | completeness | lateral RMS (cm) | corners met / evaluated | "
        "vertex error mean / median (cm) (T2) | CPU time, median of %d (s) (T3) | wall time, "
        "median (s) | raw features per CPU s |\n",
        repeats);
    std::printf("|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
    std::vector<sc::SvgPanel> panels;
    std::vector<std::pair<std::string, sc::MapMetrics>> results;
    std::vector<std::pair<std::string, FusedFeatures>> fused_by_label;
    for (const Method& m : Methods()) {
      std::vector<double> times, cpu_times;
      Run run;
      for (int r = 0; r < repeats; ++r) {
        run = Fuse(m, scans);
        times.push_back(run.seconds);
        cpu_times.push_back(run.cpu_seconds);
      }
      const sc::MapMetrics q = sc::Evaluate(world, scans, run.fused, sc::MetricsParams());
      const double t = Median(cpu_times);
      std::printf(
          "| %s | %zu | %zu / %zu | %.2f | %zu | %zu | %.3f | %.2f | %zu / %zu | %.2f / %.2f "
          "| %.3f | %.3f | %.0f |\n",
          m.label.c_str(), q.fused, q.walls_seen, q.walls_matched, q.redundancy, q.on_trivial,
          q.spurious, q.completeness, 100.0 * q.lateral_rms_m, q.corners_met, q.corners_evaluated,
          100.0 * q.vertex_error_mean_m, 100.0 * q.vertex_error_median_m, t, Median(times),
          raw / t);
      results.push_back({m.label, q});
      fused_by_label.push_back({m.label, run.fused});
      sc::SvgPanel panel;
      panel.title = m.label;
      for (const FusedFeature& f : run.fused) panel.segments.push_back(f.segment);
      if (m.label.find("midpoint") == std::string::npos) panels.push_back(std::move(panel));
    }
    // Table 2 on equal terms: the corners that every method meets.
    std::vector<size_t> common = results[0].second.met_corners;
    for (const auto& [label, q] : results) {
      std::vector<size_t> keep;
      std::set_intersection(common.begin(), common.end(), q.met_corners.begin(),
                            q.met_corners.end(), std::back_inserter(keep));
      common = keep;
    }
    std::printf(
        "\nVertex error over the %zu corners met by every method (sum of the two "
        "endpoint distances per corner, cm):\n\n| method | mean | median | max |\n"
        "|---|---|---|---|\n",
        common.size());
    for (const auto& [label, q] : results) {
      std::vector<double> e;
      for (size_t k = 0; k < q.met_corners.size(); ++k) {
        if (std::binary_search(common.begin(), common.end(), q.met_corners[k])) {
          e.push_back(q.vertex_errors_m[k]);
        }
      }
      double sum = 0.0;
      for (double x : e) sum += x;
      std::printf("| %s | %.2f | %.2f | %.2f |\n", label.c_str(),
                  e.empty() ? 0.0 : 100.0 * sum / e.size(), e.empty() ? 0.0 : 100.0 * Median(e),
                  e.empty() ? 0.0 : 100.0 * *std::max_element(e.begin(), e.end()));
    }
    // The two pairings on the same walls: endpoints more than 1 cm apart.
    const FusedFeatures* by_pairing[2] = {nullptr, nullptr};
    for (const auto& [label, fused] : fused_by_label) {
      if (label.find("mutual nearest pairing") != std::string::npos) by_pairing[0] = &fused;
      if (label.find("greedy pairing") != std::string::npos) by_pairing[1] = &fused;
    }
    if (by_pairing[0] != nullptr && by_pairing[1] != nullptr) {
      // Vertex error on the corners both pairings meet.
      const sc::MapMetrics* pm[2] = {nullptr, nullptr};
      for (const auto& [label, m] : results) {
        if (label.find("mutual nearest pairing") != std::string::npos) pm[0] = &m;
        if (label.find("greedy pairing") != std::string::npos) pm[1] = &m;
      }
      std::vector<size_t> both;
      std::set_intersection(pm[0]->met_corners.begin(), pm[0]->met_corners.end(),
                            pm[1]->met_corners.begin(), pm[1]->met_corners.end(),
                            std::back_inserter(both));
      std::printf(
          "\nCorner pairing over the %zu corners both pairings meet (vertex error, cm):\n\n"
          "| pairing | mean | median | max | corners met | lateral RMS (cm) |\n"
          "|---|---|---|---|---|---|\n",
          both.size());
      for (int k = 0; k < 2; ++k) {
        std::vector<double> e;
        for (size_t i = 0; i < pm[k]->met_corners.size(); ++i) {
          if (std::binary_search(both.begin(), both.end(), pm[k]->met_corners[i])) {
            e.push_back(pm[k]->vertex_errors_m[i]);
          }
        }
        double sum = 0.0;
        for (double x : e) sum += x;
        std::printf("| %s | %.3f | %.3f | %.3f | %zu | %.3f |\n",
                    k == 0 ? "mutual nearest" : "greedy", e.empty() ? 0.0 : 100.0 * sum / e.size(),
                    e.empty() ? 0.0 : 100.0 * Median(e),
                    e.empty() ? 0.0 : 100.0 * *std::max_element(e.begin(), e.end()),
                    pm[k]->met_corners.size(), 100.0 * pm[k]->lateral_rms_m);
      }
      size_t ends = 0, differ = 0, greedy_nearer = 0;
      double max_m = 0.0, to_corner_m[2] = {0.0, 0.0};
      for (const FusedFeature& f : *by_pairing[0]) {
        for (const FusedFeature& g : *by_pairing[1]) {
          if (g.id != f.id || g.fitted.a != f.fitted.a || g.fitted.b != f.fitted.b) continue;
          for (int end = 0; end < 2; ++end) {
            const Vec2& p = end == 0 ? f.segment.a : f.segment.b;
            const Vec2& q = end == 0 ? g.segment.a : g.segment.b;
            const double d = (p - q).norm();
            ++ends;
            max_m = std::max(max_m, d);
            if (d <= 0.01) continue;
            ++differ;
            // Which of the two lies nearer a true corner (building vertex)?
            double dp = HUGE_VAL, dq = HUGE_VAL;
            for (const sc::Corner& c : world.corners) {
              dp = std::min(dp, (c.point - p).norm());
              dq = std::min(dq, (c.point - q).norm());
            }
            to_corner_m[0] += dp;
            to_corner_m[1] += dq;
            greedy_nearer += dq < dp;
          }
        }
      }
      std::printf(
          "\nMutual nearest vs greedy pairing, on the %zu endpoints of identical walls: "
          "%zu differ by more than 1 cm, at most %.2f cm.\n",
          ends, differ, 100.0 * max_m);
      if (differ > 0) {
        std::printf(
            "Of those, greedy's is nearer the nearest true corner for %zu; mean distance to "
            "it: mutual %.2f cm, greedy %.2f cm.\n",
            greedy_nearer, 100.0 * to_corner_m[0] / differ, 100.0 * to_corner_m[1] / differ);
      }
    }
    if (!svg_dir.empty() && !world.close_pairs.empty()) {
      // A window round the first close pair, and the whole world.
      const auto& b1 = world.buildings[static_cast<size_t>(world.close_pairs[0].first)];
      const auto& b2 = world.buildings[static_cast<size_t>(world.close_pairs[0].second)];
      Vec2 lo = b1[0], hi = b1[0];
      for (const auto* b : {&b1, &b2}) {
        for (const Vec2& p : *b) {
          lo = lo.cwiseMin(p);
          hi = hi.cwiseMax(p);
        }
      }
      lo -= Vec2(4, 4);
      hi += Vec2(4, 4);
      const std::string suffix = noisy ? "-pose-noise" : "";
      mapd::Status st = sc::WriteSvg(svg_dir + "/fusion-close-pair" + suffix + ".svg", world,
                                     panels, lo, hi, 12.0);
      if (st.ok() && !noisy) {
        st = sc::WriteSvg(svg_dir + "/fusion-world.svg", world, {panels[2]}, world.min, world.max,
                          2.0);
      }
      if (!st.ok()) std::fprintf(stderr, "%s\n", st.ToString().c_str());
    }
  }
  return 0;
}

// Item 8: a world of at least 1,000,000 raw features, simulated scan by scan and
// fused as it goes (the features of a scan are dropped after Add). Only Add is timed.
int Million(int blocks_x, int blocks_y, mapd::fusion::FusionMode mode) {
  sc::ScenarioParams params;
  params.blocks_x = blocks_x;
  params.blocks_y = blocks_y;
  const sc::World world = sc::GenerateWorld(params);
  const sc::ScanSimulator sim(params, world);
  mapd::fusion::FusionParams fusion;
  fusion.mode = mode;
  if (g_occluded_gap_m >= 0.0) fusion.wall_occluded_gap_m = g_occluded_gap_m;
  if (g_occluded_ratio > 0.0) fusion.wall_occluded_gap_ratio = g_occluded_ratio;
  if (g_free_min_count > 0) fusion.wall_free_min_count = g_free_min_count;
  mapd::fusion::FusionEngine engine{fusion};
  double fuse_s = 0.0, fuse_cpu_s = 0.0;
  size_t raw = 0;
  const auto start = std::chrono::steady_clock::now();
  for (size_t k = 0; k < sim.size(); ++k) {
    const sc::Scan scan = sim.Simulate(k);
    raw += scan.features.size();
    const auto t0 = std::chrono::steady_clock::now();
    const double c0 = CpuNow();
    const mapd::Status st =
        engine.AddFrom(scan.observation, scan.robot, scan.estimated_pose.t, scan.features, nullptr);
    fuse_cpu_s += CpuNow() - c0;
    fuse_s += Seconds(t0);
    if (!st.ok()) {
      std::fprintf(stderr, "%s\n", st.ToString().c_str());
      return 1;
    }
  }
  std::printf(
      "mode %s, world %dx%d blocks: %zu buildings, %zu walls; %zu scans, %zu raw features\n",
      mapd::fusion::FusionModeName(mode), blocks_x, blocks_y, world.buildings.size(),
      world.wall_count, sim.size(), raw);
  std::printf(
      "fusion (Add only): %.2f s CPU (%.0f raw features per CPU s), %.2f s wall "
      "(%.0f/s); %zu clusters, %zu published\n",
      fuse_cpu_s, raw / fuse_cpu_s, fuse_s, raw / fuse_s, engine.cluster_count(),
      engine.published_count());
  std::printf("total incl. simulation: %.2f s; peak RSS %ld MiB\n", Seconds(start), PeakRssMiB());
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  int repeats = 5, blocks_x = 30, blocks_y = 25;
  uint64_t seed = 1;
  bool million = false;
  mapd::fusion::FusionMode mode = mapd::fusion::FusionMode::kExact;  // the paper's method
  std::string svg_dir;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    const bool has_value = i + 1 < argc;
    if (a == "--repeats" && has_value)
      repeats = std::atoi(argv[++i]);
    else if (a == "--seed" && has_value)
      seed = std::strtoull(argv[++i], nullptr, 10);
    else if (a == "--svg-dir" && has_value)
      svg_dir = argv[++i];
    else if (a == "--wall-gap" && has_value)
      g_wall_gap_m = std::atof(argv[++i]);
    else if (a == "--occluded-gap" && has_value)
      g_occluded_gap_m = std::atof(argv[++i]);
    else if (a == "--occluded-ratio" && has_value)
      g_occluded_ratio = std::atof(argv[++i]);
    else if (a == "--free-min-count" && has_value)
      g_free_min_count = std::atoi(argv[++i]);
    else if (a == "--million")
      million = true;
    else if (a == "--bounded")
      mode = mapd::fusion::FusionMode::kBounded;
    else if (a == "--blocks-x" && has_value)
      blocks_x = std::atoi(argv[++i]);
    else if (a == "--blocks-y" && has_value)
      blocks_y = std::atoi(argv[++i]);
    else {
      std::fprintf(
          stderr,
          "usage: %s [--repeats N] [--seed S] [--svg-dir DIR] [--wall-gap M] [--occluded-gap M] "
          "[--occluded-ratio R] [--free-min-count N] | --million "
          "[--blocks-x X --blocks-y Y] [--bounded]\n",
          argv[0]);
      return 2;
    }
  }
  if (million) return Million(blocks_x, blocks_y, mode);
  return Compare(std::max(1, repeats), seed, svg_dir);
}
