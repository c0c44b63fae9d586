// Real-map merge benchmark (issue 4, item 7): for each map in the shared OctoMap
// directory, cut two overlapping crops, move one by a random rigid transform
// (voxel_crops.h), and align them with our merge (MergeSubmaps, merge.h) and
// with the PCL FPFH baseline (fpfh_baseline.h) on the same trials. Prints a
// Markdown table (and writes it to --out if given). Not a test: run on demand.
//
// Each merge runs in a child process (this binary re-executed with --worker),
// so that the peak RSS reported (getrusage ru_maxrss of the child) is that of
// one merge of two .bt files, not of the benchmark.
//
//   voxel_merge_bench [--dir=DIR] [--maps=geb079.bt,...] [--overlaps=0.1,0.2,0.3,0.5]
//                     [--trials=20] [--trials-other=N] [--negatives=N] [--gap-m=2]
//                     [--methods=ours,fpfh] [--seed=1] [--max-voxels=150000]
//                     [--threads=1] [--out=FILE] [--keep-crops=DIR] [--baseline=BINARY]
//                     [--mapd[=BINARY]] [--mapd-arg=ARG ...]
//
// --trials applies to overlap 0.5, --trials-other (default = --trials) to the
// others. --negatives (default = --trials-other) pairs per map of two DISJOINT
// crops, --gap-m apart (voxel_crops.h): no merge of them is right, so every
// accepted one counts as wrong. DIR defaults to $MAPD_SHARED_DIR/data/octomap,
// else /work/shared/data/octomap; missing maps are skipped. --keep-crops copies
// every pair to DIR/<map>-<overlap>-<trial>-{a,b}.bt (overlap 0 = negative), to
// profile one merge with `--worker=ours A.bt B.bt` under perf or callgrind.
// Workers inherit the environment; run with GLIBC_TUNABLES=glibc.malloc.hugetlb=1
// to measure merges as deploy/mapd.service runs them (the table says which).
//
// --baseline=BINARY: every "ours" merge also runs in BINARY's worker (another
// build of this benchmark, e.g. of the code before a change), on the same
// crops, the two in alternating order. A second table gives per row how many
// outcomes differ (status, transform, message or pair figures, bit for bit)
// and the median of the paired CPU ratios. The machine's drift hits both
// sides of a pair alike: on a VM whose speed wandered by a third between
// runs, unpaired medians could not show a 10 % change.
//
// --mapd[=BINARY]: a real mapd (the one built beside this, or BINARY) is
// started on a temporary database with its default settings (merge.threads:
// --threads, as the library's merges here), and every "ours"
// pair is also uploaded to it and merged there (MergeSubmaps), as an operator
// would (bench/mapd_merge_client.h). A second table gives per row what the
// server decided (right / wrong / refused against the truth) and on how many
// pairs it decided differently from the library (accepted vs refused, or
// transforms more than 0.05 deg / 0.05 voxel apart). The exit code is 3 when
// any pair disagrees: the two must decide alike (issue 42 item 1).
// mapd prepares each upload for its merges in the background
// (merge.prepared_submaps_mib): the merge is sent once mapd is quiet, and
// the table gives how long that took after the uploads ("ready after").
// --mapd-arg=ARG (repeatable) passes ARG to mapd, e.g.
// --mapd-arg=--merge.prepared_submaps_mib=0 to merge from the bytes.
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <map>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "bench/fpfh_baseline.h"
#include "bench/mapd_merge_client.h"
#include "bench/voxel_crops.h"
#include "common/process.h"
#include "voxel/merge.h"
#include "voxel/octree_reader.h"
#include "voxel/voxel_grid.h"

namespace {

using mapd::Status;
using mapd::StatusCode;
using mapd::StatusOr;

double Since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

long PeakRssKb() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return usage.ru_maxrss;  // kilobytes on Linux
}

// User + system CPU seconds of this process: on a shared machine wall time
// includes waiting for a core, CPU time does not.
double CpuSeconds() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return static_cast<double>(usage.ru_utime.tv_sec + usage.ru_stime.tv_sec) +
         1e-6 * static_cast<double>(usage.ru_utime.tv_usec + usage.ru_stime.tv_usec);
}

// The system part alone: almost all of it is the kernel zeroing pages on
// first touch, whose cost on a virtual machine depends on whether the host
// still backs the guest's free memory (1 GiB of fresh huge pages took
// 0.07-2.0 s on the benchmark VM, run to run), so it is the noisy part.
double SystemCpuSeconds() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return static_cast<double>(usage.ru_stime.tv_sec) +
         1e-6 * static_cast<double>(usage.ru_stime.tv_usec);
}

StatusOr<std::string> ReadFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return Status::NotFound("cannot open " + path);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

std::vector<std::string> Split(const std::string& s, char sep) {
  std::vector<std::string> out;
  std::stringstream in(s);
  std::string item;
  while (std::getline(in, item, sep)) {
    if (!item.empty()) out.push_back(item);
  }
  return out;
}

// Figures of the accepted pair's voxel::PairReport, one table column each
// (median over the accepted merges of a row; refusals return no report). A
// new PairReport figure is one more line here.
struct PairColumn {
  const char* header;
  const char* format;
  double (*value)(const mapd::voxel::PairReport& pair, double resolution_m);
};
const PairColumn kPairColumns[] = {
    {"median matched corners", "%.0f",
     [](const mapd::voxel::PairReport& p, double) {
       return static_cast<double>(p.matched_corners);
     }},
    {"median residual (voxels)", "%.2f",
     [](const mapd::voxel::PairReport& p, double res) { return p.residual_m / res; }},
    {"median overlap score", "%.2f",
     [](const mapd::voxel::PairReport& p, double) { return p.overlap_score; }},
    // How much worse the best distinct rival that reached ICP ended; merges
    // without a rival do not count (NaN).
    {"median margin to 2nd (voxels)", "%.2f",
     [](const mapd::voxel::PairReport& p, double res) {
       return p.second_residual_m < 0 ? std::nan("") : (p.second_residual_m - p.residual_m) / res;
     }},
    // The touching-placement gate's figure (MergeParams::min_shared_free_ratio).
    {"median shared free per coinciding voxel", "%.1f",
     [](const mapd::voxel::PairReport& p, double) {
       return p.shared_free_ratio < 0 ? std::nan("") : p.shared_free_ratio;
     }},
    {"median hypotheses tried", "%.0f",
     [](const mapd::voxel::PairReport& p, double) {
       return static_cast<double>(p.hypotheses_tried);
     }},
};
constexpr std::size_t kNumPairColumns = sizeof(kPairColumns) / sizeof(kPairColumns[0]);

// ---------------------------------------------------------------------------
// Worker side: one merge, one line of results on stdout.
//   RESULT <code> <accepted> <T 16 numbers, row-major> <n stages> <stage_s>... <total_s> <rss_kb>
//   <cpu_s> STAGES <name>... PAIR <kPairColumns values> MESSAGE <text> SYSTEM <system_cpu_s>
//   STARTUP <startup_cpu_s>
// each tag starting a line; SYSTEM and STARTUP are optional (--baseline may
// run a build from before them).
struct WorkerOutput {
  StatusCode code = StatusCode::kOk;
  bool accepted = false;
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  std::vector<std::string> stage_names;
  std::vector<double> stage_s;
  double total_s = 0;
  double cpu_s = 0;                    // the whole worker process, reading the files included
  double system_cpu_s = std::nan("");  // of cpu_s (NaN: the worker did not say)
  // Of cpu_s, what came before main(): the dynamic linker's work (the
  // benchmark links PCL), which a long-running server does once, not per
  // merge. NaN: the worker did not say.
  double startup_cpu_s = std::nan("");
  std::vector<double> pair_values;  // kPairColumns of the accepted pair; empty otherwise
  std::string message;
};

// CPU seconds at the top of main() (set there, in worker mode).
double g_startup_cpu_s = 0;

// The CPU of the merge itself: from main() on when the worker says what came
// before (reading the files and freeing every map are in it), else the whole
// worker process.
double MergeCpu(const WorkerOutput& w) {
  return std::isnan(w.startup_cpu_s) ? w.cpu_s : w.cpu_s - w.startup_cpu_s;
}

void PrintWorkerOutput(const WorkerOutput& out) {
  std::printf("RESULT %d %d", static_cast<int>(out.code), out.accepted ? 1 : 0);
  for (int r = 0; r < 4; ++r) {
    for (int c = 0; c < 4; ++c) std::printf(" %.17g", out.T.matrix()(r, c));
  }
  std::printf(" %zu", out.stage_s.size());
  for (double s : out.stage_s) std::printf(" %.6f", s);
  const double system_s = SystemCpuSeconds();  // first: never above the total
  std::printf(" %.6f %ld %.3f\nSTAGES", out.total_s, PeakRssKb(), CpuSeconds());
  for (const std::string& n : out.stage_names) std::printf(" %s", n.c_str());
  std::printf("\nPAIR");
  for (double v : out.pair_values) std::printf(" %.6g", v);
  std::string msg = out.message;
  std::replace(msg.begin(), msg.end(), '\n', ' ');
  std::printf("\nMESSAGE %s\nSYSTEM %.3f\nSTARTUP %.3f\n", msg.c_str(), system_s, g_startup_cpu_s);
  std::fflush(stdout);
}

WorkerOutput RunOurs(const std::string& a, const std::string& b, int threads) {
  WorkerOutput out;
  out.stage_names = {"corners", "matching", "correlation", "alignment", "fusion", "other"};
  const auto start = std::chrono::steady_clock::now();
  mapd::voxel::MergeParams params;
  // max_seconds is a wall-clock budget: on a shared machine it trips on load,
  // not on work (two such errors in the first run, at 6 s of CPU). The
  // benchmark reports time itself, so the budget only guards against hangs.
  params.max_seconds = 600.0;
  params.threads = threads;  // --threads: MergeParams::threads
  // Threshold studies without a rebuild (the workers inherit the environment).
  if (const char* v = std::getenv("MAPD_BENCH_MAX_RESIDUAL_VOXELS"))
    params.max_residual_voxels = std::atof(v);
  if (const char* v = std::getenv("MAPD_BENCH_MIN_OVERLAP_SCORE"))
    params.min_overlap_score = std::atof(v);
  if (const char* v = std::getenv("MAPD_BENCH_CORRELATION_AFTER_CORNER_STAGES"))
    params.correlation.after_corner_stages = std::atoi(v);
  if (const char* v = std::getenv("MAPD_BENCH_MIN_SHARED_FREE_RATIO"))
    params.min_shared_free_ratio = std::atof(v);
  if (const char* v = std::getenv("MAPD_BENCH_MAX_RESTART_SPREAD_VOXELS"))
    params.max_restart_spread_voxels = std::atof(v);
  if (const char* v = std::getenv("MAPD_BENCH_MIN_MATCHED_CORNERS"))
    params.min_matched_corners = std::atoi(v);
  if (const char* v = std::getenv("MAPD_BENCH_TOP_K")) params.matching.top_k = std::atoi(v);
  if (const char* v = std::getenv("MAPD_BENCH_SCREEN_ITERATIONS"))
    params.icp_screen_iterations = std::atoi(v);
  if (const char* v = std::getenv("MAPD_BENCH_CORRELATION_MAX_CELLS"))
    params.correlation.max_cells = std::strtoull(v, nullptr, 10);
  if (const char* v = std::getenv("MAPD_BENCH_LOOSER_STAGES")) {
    params.looser_tolerances.resize(
        std::min<std::size_t>(params.looser_tolerances.size(), std::atoi(v)));
  }
  const StatusOr<mapd::voxel::MergeOutcome> r = mapd::voxel::MergeSubmaps({{1, a}, {2, b}}, params);
  out.total_s = Since(start);
  out.code = r.status().code();
  out.message = r.status().message();
  if (r.ok()) {
    // The merged map, to check that a change leaves it byte for byte the same.
    if (const char* path = std::getenv("MAPD_BENCH_MERGED_BT")) {
      std::ofstream file(path, std::ios::binary);
      file.write(r->merged_bt.data(), static_cast<std::streamsize>(r->merged_bt.size()));
      if (!file) std::fprintf(stderr, "cannot write the merged map to %s\n", path);
    }
    const auto& t = r->times;
    out.stage_s = {
        t.corners_s,
        t.matching_s,
        t.correlation_s,
        t.alignment_s,
        t.fusion_s,
        out.total_s - t.corners_s - t.matching_s - t.correlation_s - t.alignment_s - t.fusion_s};
    // The service's decision, the same function (issue 42: the two once
    // decided differently): a merge it would refuse is refused here too.
    const mapd::voxel::MergeDecision decision = mapd::voxel::DecideMerge(
        r, {1, 2}, {r->resolution, r->resolution}, params, /*review=*/false);
    if (decision.verdict == mapd::voxel::MergeVerdict::kRefused) {
      out.code = decision.reason.code();
      out.message = "the decision: " + decision.reason.message();
      return out;
    }
    out.accepted = true;
    out.T = decision.T_ref_input[1];
    for (const auto& al : r->alignments) {
      if (al.id == 2) {
        out.message = "matched=" + std::to_string(al.matched_corners) +
                      " residual_m=" + std::to_string(al.residual_m) +
                      " overlap=" + std::to_string(al.overlap_score);
      }
    }
    for (const auto& pair : r->pairs) {
      if (!pair.accepted) continue;
      out.message += " shared_free=" + std::to_string(pair.shared_free_ratio) +
                     " restart_spread=" + std::to_string(pair.restart_spread_voxels);
      for (const PairColumn& column : kPairColumns) {
        out.pair_values.push_back(column.value(pair, r->resolution));
      }
    }
  } else {
    out.stage_s = {0, 0, 0, 0, 0, out.total_s};
  }
  return out;
}

WorkerOutput RunFpfh(const std::string& a, const std::string& b, int threads, unsigned seed) {
  WorkerOutput out;
  out.stage_names = {"load", "downsample", "normals", "features", "ransac", "icp"};
  const auto start = std::chrono::steady_clock::now();
  std::vector<Eigen::Vector3d> pts[2];
  double resolution = 0;
  const std::string* bytes[2] = {&a, &b};
  for (int i = 0; i < 2; ++i) {
    StatusOr<mapd::voxel::OcTreePtr> tree = mapd::voxel::ReadOctree(*bytes[i]);
    if (!tree.ok()) {
      out.code = tree.status().code();
      out.message = tree.status().message();
      return out;
    }
    StatusOr<mapd::voxel::VoxelGrid> grid = mapd::voxel::VoxelGrid::FromOcTree(**tree);
    if (!grid.ok()) {
      out.code = grid.status().code();
      out.message = grid.status().message();
      return out;
    }
    pts[i] = grid->occupied_centres();
    resolution = grid->resolution();
  }
  const double load_s = Since(start);
  mapd::bench::FpfhParams params;
  params.threads = threads;
  params.seed = seed;
  StatusOr<mapd::bench::FpfhResult> r = mapd::bench::AlignFpfh(pts[0], pts[1], resolution, params);
  out.total_s = Since(start);
  if (!r.ok()) {
    out.code = r.status().code();
    out.message = r.status().message();
    return out;
  }
  const auto& t = r->times;
  out.stage_s = {load_s, t.downsample_s, t.normals_s, t.features_s, t.ransac_s, t.icp_s};
  out.accepted = r->accepted;
  out.T = r->T_a_b;
  // The baseline's refusal: RANSAC found no pose with enough inliers.
  if (!r->accepted) out.code = StatusCode::kFailedPrecondition;
  out.message = "points=" + std::to_string(r->points_a) + "/" + std::to_string(r->points_b) +
                " inliers=" + std::to_string(r->ransac_inlier_fraction) +
                " icp_fitness_m2=" + std::to_string(r->icp_fitness_m2);
  return out;
}

int WorkerMain(const std::string& method, const std::string& path_a, const std::string& path_b,
               int threads, unsigned seed) {
  StatusOr<std::string> a = ReadFile(path_a), b = ReadFile(path_b);
  if (!a.ok() || !b.ok()) {
    std::fprintf(stderr, "worker: cannot read inputs\n");
    return 2;
  }
  PrintWorkerOutput(method == "ours" ? RunOurs(*a, *b, threads) : RunFpfh(*a, *b, threads, seed));
  return 0;
}

// ---------------------------------------------------------------------------
// Parent side.
struct Options {
  std::string dir;
  std::vector<std::string> maps = {"geb079.bt", "fr_078_tidyup.bt", "new_college.bt"};
  std::vector<double> overlaps = {0.1, 0.2, 0.3, 0.5};
  std::vector<std::string> methods = {"ours", "fpfh"};
  int trials = 20;
  int trials_other = -1;
  int negatives = -1;
  double gap_m = 2.0;
  unsigned seed = 1;
  std::size_t max_voxels = 150'000;
  int threads = 1;
  std::string out;
  std::string keep_crops;  // --keep-crops: where to copy every crop pair
  std::string baseline;    // --baseline: another build's binary, run on every "ours" pair
  std::string mapd;        // --mapd: the mapd binary to merge every "ours" pair through
  std::vector<std::string> mapd_args;  // --mapd-arg: more of mapd's command line
};

// Runs one worker process; FAILED status INTERNAL when it crashed or timed out.
WorkerOutput RunWorker(const std::string& self, const std::string& method,
                       const std::string& path_a, const std::string& path_b, int threads,
                       unsigned seed, long* rss_kb) {
  WorkerOutput out;
  out.code = StatusCode::kInternal;
  *rss_kb = 0;
  const std::string cmd = "timeout 900 '" + self + "' --worker=" + method + " '" + path_a + "' '" +
                          path_b + "' --threads=" + std::to_string(threads) +
                          " --seed=" + std::to_string(seed);
  FILE* pipe = popen(cmd.c_str(), "r");
  if (pipe == nullptr) {
    out.message = "popen failed";
    return out;
  }
  std::string text;
  char buf[4096];
  while (std::fgets(buf, sizeof(buf), pipe) != nullptr) text += buf;
  const int rc = pclose(pipe);
  std::istringstream in(text);
  std::string line;
  bool got = false;
  while (std::getline(in, line)) {
    std::istringstream ls(line);
    std::string tag;
    ls >> tag;
    if (tag == "RESULT") {
      int code = 0, accepted = 0;
      std::size_t n = 0;
      ls >> code >> accepted;
      for (int r = 0; r < 4; ++r) {
        for (int c = 0; c < 4; ++c) ls >> out.T.matrix()(r, c);
      }
      ls >> n;
      out.stage_s.resize(n);
      for (double& s : out.stage_s) ls >> s;
      ls >> out.total_s >> *rss_kb >> out.cpu_s;
      out.code = static_cast<StatusCode>(code);
      out.accepted = accepted != 0;
      got = static_cast<bool>(ls);
    } else if (tag == "STAGES") {
      std::string name;
      while (ls >> name) out.stage_names.push_back(name);
    } else if (tag == "PAIR") {
      // strtod, not >>: a column may be "nan" (no value for this merge).
      std::string v;
      while (ls >> v) out.pair_values.push_back(std::strtod(v.c_str(), nullptr));
    } else if (tag == "MESSAGE") {
      std::getline(ls, out.message);
    } else if (tag == "SYSTEM") {
      ls >> out.system_cpu_s;
    } else if (tag == "STARTUP") {
      ls >> out.startup_cpu_s;
    }
  }
  if (!got) {
    out.code = StatusCode::kInternal;
    out.accepted = false;
    out.message = "worker crashed or timed out (wait status " + std::to_string(rc) + ")";
  }
  return out;
}

// Whether two workers' outcomes are the same, bit for bit (timings aside).
bool SameOutcome(const WorkerOutput& x, const WorkerOutput& y) {
  if (x.code != y.code || x.accepted != y.accepted || x.message != y.message ||
      !(x.T.matrix().array() == y.T.matrix().array()).all() ||
      x.pair_values.size() != y.pair_values.size()) {
    return false;
  }
  for (std::size_t i = 0; i < x.pair_values.size(); ++i) {
    const double a = x.pair_values[i], b = y.pair_values[i];
    if (!(a == b || (std::isnan(a) && std::isnan(b)))) return false;
  }
  return true;
}

double Median(std::vector<double> v) {
  if (v.empty()) return std::nan("");
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 == 1 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

struct Row {
  std::string map, method;
  double resolution = 0, overlap = 0;
  bool negative = false;  // disjoint crops: every accepted merge is wrong
  int trials = 0, success = 0, wrong = 0, refused = 0, errors = 0;
  std::vector<double> rot_deg, trans_vox, total_s, cpu_s, cpu_refused_s, achieved, crop_a, crop_b;
  std::vector<double> system_cpu_s;  // the part of cpu_s that was the kernel's
  std::vector<double> free_a, free_b;
  std::vector<std::vector<double>> pair_values;  // per kPairColumns
  std::vector<std::string> stage_names;
  std::vector<std::vector<double>> stage_s;
  long peak_rss_kb = 0;
  std::map<std::string, int> error_messages;
  // --mapd: the server's verdicts on the same pairs.
  int mapd_runs = 0, mapd_right = 0, mapd_wrong = 0, mapd_refused = 0, mapd_errors = 0;
  int mapd_disagree = 0;
  // The MergeSubmaps call alone: wall, mapd's CPU meanwhile (all threads),
  // and that CPU for the refused merges.
  std::vector<double> mapd_wall_s, mapd_cpu_s, mapd_refused_cpu_s, mapd_ready_s;
  // --baseline: pairs run, outcomes that differ, its CPU, and this build's
  // over its per pair (crashed workers count as differing, with no CPU).
  int baseline_runs = 0, baseline_differs = 0;
  std::vector<double> baseline_cpu_s, cpu_ratio;
  std::vector<double> paired_cpu_s;    // this build's, measured as baseline_cpu_s is
  std::vector<double> user_cpu_ratio;  // CPU less system CPU, where both workers said
};

std::string Fmt(const char* fmt, double v) {
  if (std::isnan(v)) return "-";
  char buf[64];
  std::snprintf(buf, sizeof(buf), fmt, v);
  return buf;
}

std::string RowToMarkdown(const Row& row) {
  std::ostringstream s;
  std::string stages;
  for (std::size_t i = 0; i < row.stage_names.size(); ++i) {
    std::vector<double> v;
    for (const auto& t : row.stage_s) {
      if (i < t.size()) v.push_back(t[i]);
    }
    if (!stages.empty()) stages += ", ";
    stages += row.stage_names[i] + " " + Fmt("%.2f", Median(v));
  }
  const double max_cpu =
      row.cpu_s.empty() ? std::nan("") : *std::max_element(row.cpu_s.begin(), row.cpu_s.end());
  s << "| " << row.map << " | " << row.resolution << " | "
    << (row.negative ? std::string("none (disjoint)")
                     : Fmt("%.1f", row.overlap) + " / " + Fmt("%.2f", Median(row.achieved)))
    << " | " << Fmt("%.0f", Median(row.crop_a)) << " / " << Fmt("%.0f", Median(row.crop_b)) << " | "
    << Fmt("%.0f", Median(row.free_a)) << " / " << Fmt("%.0f", Median(row.free_b)) << " | "
    << row.method << " | " << row.success << "/" << row.trials << " ("
    << Fmt("%.0f", 100.0 * row.success / std::max(1, row.trials)) << " %) | " << row.wrong << " | "
    << row.refused << " | " << row.errors << " | " << Fmt("%.2f", Median(row.rot_deg)) << " | "
    << Fmt("%.2f", Median(row.trans_vox)) << " | " << stages << " | "
    << Fmt("%.2f", Median(row.total_s)) << " | " << Fmt("%.2f", Median(row.cpu_s)) << " | "
    << Fmt("%.2f", Median(row.system_cpu_s)) << " | " << Fmt("%.2f", Median(row.cpu_refused_s))
    << " | " << Fmt("%.2f", max_cpu) << " | ";
  for (std::size_t i = 0; i < kNumPairColumns; ++i) {
    s << Fmt(kPairColumns[i].format,
             i < row.pair_values.size() ? Median(row.pair_values[i]) : std::nan(""))
      << " | ";
  }
  s << Fmt("%.0f", row.peak_rss_kb / 1024.0) << " |\n";
  return s.str();
}

// The Markdown table of `rows`, on stdout when final, and (re)written to `out`
// after every trial so that an interrupted run still leaves its table.
void WriteTable(const std::vector<Row>& rows, const std::string& out_path, bool final) {
  std::ostringstream table;
  table << "| map | res (m) | overlap req / achieved | occupied voxels A / B | free voxels A / B | "
           "method | right | wrong | refused | errors | median rot err (deg) | median trans err "
           "(voxels) | median stage times (s) | median total (s) | median CPU (s) | median system "
           "CPU (s) | median CPU of refusals (s) | max CPU (s) | ";
  for (const PairColumn& column : kPairColumns) table << column.header << " | ";
  table << "peak RSS (MiB) |\n|";
  for (std::size_t i = 0; i < 19 + kNumPairColumns; ++i) table << "---|";
  table << "\n";
  for (const Row& r : rows) table << RowToMarkdown(r);
  if (std::any_of(rows.begin(), rows.end(), [](const Row& r) { return r.baseline_runs > 0; })) {
    table << "\nAgainst --baseline (paired on the same crops, alternating order):\n\n"
             "| map | overlap | method | outcomes differing | median CPU, baseline (s) | "
             "median CPU, this build (s) | median CPU ratio, this / baseline | median user "
             "CPU ratio |\n"
             "|---|---|---|---|---|---|---|---|\n";
    for (const Row& r : rows) {
      if (r.baseline_runs == 0) continue;
      table << "| " << r.map << " | "
            << (r.negative ? std::string("none (disjoint)") : Fmt("%.1f", r.overlap)) << " | "
            << r.method << " | " << r.baseline_differs << " of " << r.baseline_runs << " | "
            << Fmt("%.2f", Median(r.baseline_cpu_s)) << " | " << Fmt("%.2f", Median(r.paired_cpu_s))
            << " | " << Fmt("%.3f", Median(r.cpu_ratio)) << " | "
            << Fmt("%.3f", Median(r.user_cpu_ratio)) << " |\n";
    }
  }
  // The workers inherit the environment: say how their malloc ran (huge
  // pages or not moves a campus merge's CPU by 20-30 %, docs/operations.md).
  const char* tunables = std::getenv("GLIBC_TUNABLES");
  table << "\nWorkers ran with GLIBC_TUNABLES=" << (tunables == nullptr ? "(unset)" : tunables)
        << "\n";
  std::ostringstream notes;
  for (const Row& r : rows) {
    for (const auto& [msg, count] : r.error_messages) {
      notes << "- " << r.map << " " << r.method << " overlap " << r.overlap << ": " << count
            << " x " << msg << "\n";
    }
  }
  if (final) {
    std::cout << table.str();
    if (!notes.str().empty()) std::cout << "\nErrors:\n\n" << notes.str();
  }
  if (!out_path.empty()) {
    std::ofstream out(out_path);
    out << table.str();
    if (!notes.str().empty()) out << "\nErrors:\n\n" << notes.str();
    if (final) std::cerr << "wrote " << out_path << "\n";
  }
}

// The global map builds in a mapd log (event=global_map_built lines): how
// many, their median and largest seconds, and the last one's members and
// occupied voxels, as a Markdown list item.
std::string GlobalMapBuilds(const std::string& map, const std::string& log) {
  std::vector<double> seconds;
  std::string members = "0", occupied = "0";
  const auto field = [](const std::string& line, const std::string& key) {
    const size_t at = line.find(" " + key + "=");
    if (at == std::string::npos) return std::string();
    const size_t start = at + key.size() + 2;
    return line.substr(start, line.find(' ', start) - start);
  };
  std::istringstream in(log);
  for (std::string line; std::getline(in, line);) {
    if (line.find("event=global_map_built") == std::string::npos) continue;
    seconds.push_back(std::atof(field(line, "s").c_str()));
    members = field(line, "members");
    occupied = field(line, "occupied_voxels");
  }
  if (seconds.empty()) return "- " + map + ": no build\n";
  return "- " + map + ": " + std::to_string(seconds.size()) + " builds, median " +
         Fmt("%.2f", Median(seconds)) + " s, largest " +
         Fmt("%.2f", *std::max_element(seconds.begin(), seconds.end())) + " s; the last of " +
         members + " members, " + occupied + " occupied voxels\n";
}

// --mapd's table: what the server decided on the same pairs.
void WriteMapdTable(const std::vector<Row>& rows, const std::string& out_path) {
  std::ostringstream table;
  table << "\nThrough mapd (upload, MergeSubmaps), the same pairs:\n\n"
        << "| map | overlap | method | pairs | mapd right | mapd wrong | mapd refused | mapd "
           "errors | decided unlike the library | median wall (s) | median mapd CPU (s) | "
           "median mapd CPU of refusals (s) | median ready after the uploads (s) "
           "|\n|---|---|---|---|---|---|---|---|---|---|---|---|---|\n";
  for (const Row& r : rows) {
    if (r.mapd_runs == 0) continue;
    table << "| " << r.map << " | "
          << (r.negative ? std::string("disjoint") : Fmt("%.1f", r.overlap)) << " | " << r.method
          << " | " << r.mapd_runs << " | " << r.mapd_right << " | " << r.mapd_wrong << " | "
          << r.mapd_refused << " | " << r.mapd_errors << " | " << r.mapd_disagree << " | "
          << Fmt("%.2f", Median(r.mapd_wall_s)) << " | " << Fmt("%.2f", Median(r.mapd_cpu_s))
          << " | " << Fmt("%.2f", Median(r.mapd_refused_cpu_s)) << " | "
          << Fmt("%.1f", Median(r.mapd_ready_s)) << " |\n";
  }
  std::cout << table.str();
  if (!out_path.empty()) std::ofstream(out_path, std::ios::app) << table.str();
}

bool ParseOptions(int argc, char** argv, Options* o) {
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    const auto eq = arg.find('=');
    const std::string key = arg.substr(0, eq);
    const std::string val = eq == std::string::npos ? "" : arg.substr(eq + 1);
    if (key == "--dir") {
      o->dir = val;
    } else if (key == "--maps") {
      o->maps = Split(val, ',');
    } else if (key == "--overlaps") {
      o->overlaps.clear();
      for (const std::string& v : Split(val, ',')) o->overlaps.push_back(std::atof(v.c_str()));
    } else if (key == "--methods") {
      o->methods = Split(val, ',');
    } else if (key == "--trials") {
      o->trials = std::atoi(val.c_str());
    } else if (key == "--trials-other") {
      o->trials_other = std::atoi(val.c_str());
    } else if (key == "--negatives") {
      o->negatives = std::atoi(val.c_str());
    } else if (key == "--gap-m") {
      o->gap_m = std::atof(val.c_str());
    } else if (key == "--seed") {
      o->seed = static_cast<unsigned>(std::strtoul(val.c_str(), nullptr, 10));
    } else if (key == "--max-voxels") {
      o->max_voxels = std::strtoul(val.c_str(), nullptr, 10);
    } else if (key == "--threads") {
      o->threads = std::atoi(val.c_str());
    } else if (key == "--out") {
      o->out = val;
    } else if (key == "--keep-crops") {
      o->keep_crops = val;
    } else if (key == "--baseline") {
      o->baseline = val;
    } else if (key == "--mapd") {
      o->mapd = eq == std::string::npos ? MAPD_BINARY : val;
    } else if (key == "--mapd-arg") {
      o->mapd_args.push_back(val);
    } else {
      std::fprintf(stderr, "unknown flag %s (see the header of voxel_merge_bench.cc)\n",
                   arg.c_str());
      return false;
    }
  }
  for (const std::string& m : o->methods) {
    if (m != "ours" && m != "fpfh") {
      std::fprintf(stderr, "--methods: unknown method %s\n", m.c_str());
      return false;
    }
  }
  for (double f : o->overlaps) {
    if (!(f > 0 && f < 1)) {
      std::fprintf(stderr, "--overlaps: %g is not in (0, 1)\n", f);
      return false;
    }
  }
  if (o->trials_other < 0) o->trials_other = o->trials;
  if (o->negatives < 0) o->negatives = o->trials_other;
  return o->trials >= 0 && o->threads >= 1;
}

}  // namespace

int main(int argc, char** argv) {
  // Worker mode: --worker=METHOD A.bt B.bt [--threads=N] [--seed=S]
  if (argc >= 4 && std::string(argv[1]).rfind("--worker=", 0) == 0) {
    g_startup_cpu_s = CpuSeconds();
    int threads = 1;
    unsigned seed = 1;
    for (int i = 4; i < argc; ++i) {
      const std::string a = argv[i];
      if (a.rfind("--threads=", 0) == 0) threads = std::atoi(a.c_str() + 10);
      if (a.rfind("--seed=", 0) == 0) seed = static_cast<unsigned>(std::atol(a.c_str() + 7));
    }
    return WorkerMain(std::string(argv[1]).substr(9), argv[2], argv[3], threads, seed);
  }
  Options opt;
  if (!ParseOptions(argc, argv, &opt)) return 2;
  if (opt.dir.empty()) {
    const char* shared = std::getenv("MAPD_SHARED_DIR");
    opt.dir = std::string(shared != nullptr ? shared : "/work/shared") + "/data/octomap";
  }
  char self[4096];
  const ssize_t len = readlink("/proc/self/exe", self, sizeof(self) - 1);
  if (len <= 0) return 1;
  self[len] = '\0';
  char tmpl[] = "/tmp/voxel_merge_bench.XXXXXX";
  const char* tmp = mkdtemp(tmpl);
  if (tmp == nullptr) return 1;
  const std::string path_a = std::string(tmp) + "/a.bt", path_b = std::string(tmp) + "/b.bt";

  std::vector<Row> rows;
  // --mapd: one mapd per map, as a site runs one per building: the maps'
  // crops share no frame, and one map's global map (every placed upload,
  // built in the background after each accepted merge) must not weigh on the
  // next map's merges. Its database goes with it.
  mapd::testing::MapdProcess mapd_process;
  std::unique_ptr<mapd::bench::MapdMergeClient> mapd_client;
  std::string mapd_map;                       // the map the running mapd merges
  std::vector<std::string> global_map_lines;  // per map: its global map builds
  const auto stop_mapd = [&] {
    if (!mapd_client) return;
    global_map_lines.push_back(GlobalMapBuilds(mapd_map, mapd_process.log()));
    mapd_client.reset();
    mapd::testing::Stop(mapd_process.pid);
    for (const char* file : {"/mapd.db", "/mapd.db-wal", "/mapd.db-shm", "/mapd.db.log"})
      std::remove((std::string(tmp) + file).c_str());
  };
  const auto start_mapd = [&]() -> bool {
    stop_mapd();
    if (opt.mapd.empty()) return true;
    std::vector<std::string> args = {"--http.port", "0", "--merge.threads",
                                     std::to_string(opt.threads)};
    args.insert(args.end(), opt.mapd_args.begin(), opt.mapd_args.end());
    mapd_process = mapd::testing::StartMapd(std::string(tmp) + "/mapd.db", args, opt.mapd);
    if (mapd_process.port == 0) {
      std::fprintf(stderr, "--mapd: %s did not start:\n%s\n", opt.mapd.c_str(),
                   mapd_process.log().c_str());
      return false;
    }
    mapd_client =
        std::make_unique<mapd::bench::MapdMergeClient>(mapd_process.address, mapd_process.pid);
    return true;
  };
  for (std::size_t mi = 0; mi < opt.maps.size(); ++mi) {
    const std::string path = opt.dir + "/" + opt.maps[mi];
    StatusOr<mapd::voxel::OcTreePtr> tree = mapd::voxel::ReadOctreeFile(path);
    if (!tree.ok()) {
      std::fprintf(stderr, "skipping %s: %s\n", path.c_str(), tree.status().ToString().c_str());
      continue;
    }
    StatusOr<mapd::voxel::VoxelGrid> grid = mapd::voxel::VoxelGrid::FromOcTree(**tree);
    if (!grid.ok()) {
      std::fprintf(stderr, "skipping %s: %s\n", path.c_str(), grid.status().ToString().c_str());
      continue;
    }
    tree->reset();  // release the octree: the grid is all we need
    stop_mapd();    // the previous map's, with its name
    mapd_map = opt.maps[mi];
    if (!start_mapd()) return 1;
    // The overlaps, then the negative pairs (overlap 0: disjoint crops).
    std::vector<double> cases = opt.overlaps;
    if (opt.negatives > 0) cases.push_back(0.0);
    for (const double overlap : cases) {
      const bool negative = overlap == 0.0;
      const int trials = negative                         ? opt.negatives
                         : std::abs(overlap - 0.5) < 1e-9 ? opt.trials
                                                          : opt.trials_other;
      std::vector<Row> method_rows(opt.methods.size());
      for (std::size_t k = 0; k < opt.methods.size(); ++k) {
        method_rows[k].map = opt.maps[mi];
        method_rows[k].method = opt.methods[k];
        method_rows[k].resolution = grid->resolution();
        method_rows[k].overlap = overlap;
        method_rows[k].negative = negative;
        method_rows[k].pair_values.resize(kNumPairColumns);
      }
      for (int trial = 0; trial < trials; ++trial) {
        mapd::bench::CropParams cp;
        cp.disjoint = negative;
        if (!negative) cp.overlap = overlap;
        cp.gap_m = opt.gap_m;
        cp.max_occupied_per_crop = opt.max_voxels;
        cp.seed = mapd::bench::TrialSeed(opt.seed, opt.maps[mi], overlap, trial);
        const auto gen_start = std::chrono::steady_clock::now();
        StatusOr<mapd::bench::CropPair> pair = mapd::bench::MakeCropPair(*grid, cp);
        const double gen_s = Since(gen_start);
        if (!pair.ok()) {
          std::fprintf(stderr, "%s overlap %.1f trial %d: crop failed: %s\n", opt.maps[mi].c_str(),
                       overlap, trial, pair.status().ToString().c_str());
          continue;
        }
        std::ofstream(path_a, std::ios::binary) << pair->a_bt;
        std::ofstream(path_b, std::ios::binary) << pair->b_bt;
        if (!opt.keep_crops.empty()) {
          const std::string stem = opt.keep_crops + "/" + opt.maps[mi] + "-" +
                                   Fmt("%.2f", overlap) + "-" + std::to_string(trial);
          std::ofstream(stem + "-a.bt", std::ios::binary) << pair->a_bt;
          std::ofstream(stem + "-b.bt", std::ios::binary) << pair->b_bt;
        }
        std::fprintf(stderr,
                     "%s overlap %.1f trial %d: crops %zu/%zu (out %zu/%zu occ, %zu/%zu free), "
                     "achieved %.3f, yaw %.1f roll %.1f pitch %.1f t %.1f m, gen %.2f s\n",
                     opt.maps[mi].c_str(), overlap, trial, pair->occupied_a, pair->occupied_b,
                     pair->out_occupied_a, pair->out_occupied_b, pair->out_free_a, pair->out_free_b,
                     pair->achieved_overlap, pair->yaw_deg, pair->roll_deg, pair->pitch_deg,
                     pair->translation_m, gen_s);
        for (std::size_t k = 0; k < opt.methods.size(); ++k) {
          Row& row = method_rows[k];
          long rss_kb = 0, baseline_rss_kb = 0;
          const bool paired = !opt.baseline.empty() && opt.methods[k] == "ours";
          const auto run_baseline = [&] {
            return RunWorker(opt.baseline, opt.methods[k], path_a, path_b, opt.threads,
                             static_cast<unsigned>(cp.seed), &baseline_rss_kb);
          };
          // Alternating which runs first, so that neither side always meets
          // a cold cache or the other's freed memory.
          WorkerOutput base;
          if (paired && trial % 2 == 1) base = run_baseline();
          const WorkerOutput w = RunWorker(self, opt.methods[k], path_a, path_b, opt.threads,
                                           static_cast<unsigned>(cp.seed), &rss_kb);
          if (paired && trial % 2 == 0) base = run_baseline();
          if (paired) {
            const bool same = SameOutcome(w, base);
            ++row.baseline_runs;
            row.baseline_differs += same ? 0 : 1;
            const bool timed =
                w.code != StatusCode::kInternal && base.code != StatusCode::kInternal;
            // Both from main() on, or (a baseline from before STARTUP) both whole.
            const bool net = !std::isnan(w.startup_cpu_s) && !std::isnan(base.startup_cpu_s);
            const double cpu = net ? MergeCpu(w) : w.cpu_s;
            const double base_cpu = net ? MergeCpu(base) : base.cpu_s;
            if (base.code != StatusCode::kInternal) row.baseline_cpu_s.push_back(base_cpu);
            if (w.code != StatusCode::kInternal) row.paired_cpu_s.push_back(cpu);
            if (timed && base_cpu > 0) row.cpu_ratio.push_back(cpu / base_cpu);
            const double user = cpu - w.system_cpu_s;
            const double base_user = base_cpu - base.system_cpu_s;
            if (timed && base_user > 0)
              row.user_cpu_ratio.push_back(user / base_user);  // NaN fails
            std::fprintf(stderr, "  baseline: %s, cpu %.2f s |%s\n",
                         same ? "same outcome" : "DIFFERS", MergeCpu(base),
                         same ? "" : base.message.c_str());
          }
          ++row.trials;
          row.achieved.push_back(pair->achieved_overlap);
          row.crop_a.push_back(static_cast<double>(pair->out_occupied_a));
          row.crop_b.push_back(static_cast<double>(pair->out_occupied_b));
          row.free_a.push_back(static_cast<double>(pair->out_free_a));
          row.free_b.push_back(static_cast<double>(pair->out_free_b));
          row.peak_rss_kb = std::max(row.peak_rss_kb, rss_kb);
          if (row.stage_names.empty()) row.stage_names = w.stage_names;
          if (w.code != StatusCode::kInternal) {
            row.stage_s.push_back(w.stage_s);
            row.total_s.push_back(w.total_s);
            row.cpu_s.push_back(MergeCpu(w));
            if (!std::isnan(w.system_cpu_s)) row.system_cpu_s.push_back(w.system_cpu_s);
          }
          std::string verdict;
          if (w.accepted && w.code == StatusCode::kOk) {
            for (std::size_t i = 0; i < kNumPairColumns && i < w.pair_values.size(); ++i) {
              if (!std::isnan(w.pair_values[i])) row.pair_values[i].push_back(w.pair_values[i]);
            }
          }
          if (w.accepted && w.code == StatusCode::kOk && negative) {
            ++row.wrong;  // disjoint crops: nothing to merge
            verdict = "WRONG (disjoint crops merged)";
          } else if (w.accepted && w.code == StatusCode::kOk) {
            const double rot = mapd::bench::RotationErrorDeg(w.T, pair->T_a_b);
            const double trans_m =
                mapd::bench::TranslationErrorAt(w.T, pair->T_a_b, pair->centroid_b);
            const double trans_vox = trans_m / grid->resolution();
            row.rot_deg.push_back(rot);
            row.trans_vox.push_back(trans_vox);
            const bool ok = rot < 2.0 && trans_vox < 2.0;
            ++(ok ? row.success : row.wrong);
            char buf[128];
            std::snprintf(buf, sizeof(buf), "%s rot %.3f deg trans %.2f vox", ok ? "OK" : "WRONG",
                          rot, trans_vox);
            verdict = buf;
          } else if (w.code == StatusCode::kFailedPrecondition) {
            ++row.refused;
            row.cpu_refused_s.push_back(MergeCpu(w));
            verdict = "REFUSED";
          } else {
            ++row.errors;
            verdict = std::string("ERROR ") + mapd::StatusCodeName(w.code);
            ++row.error_messages[verdict + ": " + w.message.substr(0, 120)];
          }
          std::fprintf(stderr, "  %-4s %-40s %.2f s (cpu %.2f s), peak %.0f MiB |%s\n",
                       opt.methods[k].c_str(), verdict.c_str(), w.total_s, MergeCpu(w),
                       rss_kb / 1024.0, w.message.c_str());
          if (mapd_client && opt.methods[k] == "ours") {
            const std::string name =
                opt.maps[mi] + "-" + Fmt("%.2f", overlap) + "-" + std::to_string(trial);
            const mapd::bench::MapdVerdict v = mapd_client->Merge(name, pair->a_bt, pair->b_bt);
            ++row.mapd_runs;
            row.mapd_wall_s.push_back(v.merge_wall_s);
            row.mapd_ready_s.push_back(v.background_wait_s);
            if (v.mapd_cpu_s >= 0) {
              row.mapd_cpu_s.push_back(v.mapd_cpu_s);
              if (v.answered && !v.accepted) row.mapd_refused_cpu_s.push_back(v.mapd_cpu_s);
            }
            std::string said;
            if (!v.answered) {
              ++row.mapd_errors;
              said = "ERROR " + v.code;
            } else if (!v.accepted) {
              ++row.mapd_refused;
              said = "REFUSED";
            } else if (negative) {
              ++row.mapd_wrong;
              said = "WRONG (disjoint crops merged)";
            } else {
              const double rot = mapd::bench::RotationErrorDeg(v.T_a_b, pair->T_a_b);
              const double vox =
                  mapd::bench::TranslationErrorAt(v.T_a_b, pair->T_a_b, pair->centroid_b) /
                  grid->resolution();
              const bool ok = rot < 2.0 && vox < 2.0;
              ++(ok ? row.mapd_right : row.mapd_wrong);
              char buf[128];
              std::snprintf(buf, sizeof(buf), "%s rot %.3f deg trans %.2f vox", ok ? "OK" : "WRONG",
                            rot, vox);
              said = buf;
            }
            const bool library_accepted = w.accepted && w.code == StatusCode::kOk;
            bool agree = v.answered && v.accepted == library_accepted;
            if (agree && v.accepted) {
              agree = mapd::bench::RotationErrorDeg(v.T_a_b, w.T) < 0.05 &&
                      mapd::bench::TranslationErrorAt(v.T_a_b, w.T, pair->centroid_b) /
                              grid->resolution() <
                          0.05;
            }
            row.mapd_disagree += agree ? 0 : 1;
            std::fprintf(stderr,
                         "  mapd %-40s %s, %.2f s (mapd cpu %.2f s, system %.2f s; quiet after "
                         "%.1f s) |%s\n",
                         said.c_str(), agree ? "as the library" : "UNLIKE THE LIBRARY",
                         v.merge_wall_s, v.mapd_cpu_s, v.mapd_system_cpu_s, v.background_wait_s,
                         v.message.c_str());
          }
          std::string stage_log;
          for (std::size_t i = 0; i < w.stage_s.size() && i < w.stage_names.size(); ++i) {
            stage_log += " " + w.stage_names[i] + "=" + Fmt("%.2f", w.stage_s[i]);
          }
          std::fprintf(stderr, "       stages:%s\n", stage_log.c_str());
        }
        std::vector<Row> so_far = rows;
        so_far.insert(so_far.end(), method_rows.begin(), method_rows.end());
        WriteTable(so_far, opt.out, /*final=*/false);
      }
      for (Row& r : method_rows) rows.push_back(std::move(r));
    }
  }
  stop_mapd();
  std::remove(path_a.c_str());
  std::remove(path_b.c_str());
  rmdir(tmp);

  WriteTable(rows, opt.out, /*final=*/true);
  if (opt.mapd.empty()) return 0;
  WriteMapdTable(rows, opt.out);
  std::string builds =
      "\nThe global map (every placed upload of the map's mapd), built in the "
      "background after each accepted merge:\n\n";
  for (const std::string& line : global_map_lines) builds += line;
  std::cout << builds;
  if (!opt.out.empty()) std::ofstream(opt.out, std::ios::app) << builds;
  int disagree = 0;
  for (const Row& r : rows) disagree += r.mapd_disagree;
  return disagree == 0 ? 0 : 3;
}
