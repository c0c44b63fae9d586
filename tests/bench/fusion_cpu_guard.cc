// CPU guard for the fuser with free-space evidence on (issue 40 item 3).
//
// Evidence made fusion ~5x costlier before anyone noticed: the soak is run by
// hand, never in CI. This program runs a fixed workload in one engine, the
// soak's city (docs/long-running.md, "The synthetic city": 4 x 3 blocks, 8
// robots each driving the route from its own starting point, a centimetre of
// fresh pose jitter per scan, bounded mode, default settings, every scan
// added with its sensor origin), and measures fused raw features per
// CPU-second of this process (getrusage: the machine's other load does not
// count, unlike wall time). It fails (exit 1) when three runs in a row are
// each below half the figure the doc states for this workload: a
// regression of the kind that made the soak 5x slower fails it on any machine
// within 2x of the doc's, and one run slowed by a busy host does not.
//
// The engine alone does less than the soak's fuser thread (no projection, no
// database rows, no robots on the same cores); half of the stated figure is
// the alarm, not the target.
//
//   fusion_cpu_guard [--features N] [--origin pose|soak|none] [--min-ratio R]
//                    [--retire-views N] [--refit-tolerance M]
//
// --origin soak feeds the sensor origin the soak's city batches carried
// before issue 40 (the map origin plus the jitter: the batches' lines were in
// the map frame, T_frame_sensor the identity), to measure that workload.
// --origin none adds the scans without one: no evidence, for comparison.
// --retire-views 0 turns retirement off (fusion.retire_views), for comparison.
// --refit-tolerance 0 re-resolves every refit (fusion.refit_tolerance_m), for
// comparison.
// deploy/test.sh runs it after ctest, with the defaults.
#include <sys/resource.h>

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <random>
#include <string>
#include <vector>

#include "fusion/engine.h"
#include "sim/city_scenario.h"

namespace {

namespace sc = mapd::fusion::scenario;
using mapd::fusion::GroundFeature;
using mapd::geometry::Vec2;

// docs/long-running.md, "The CPU guard": the figure this workload's fused
// features per CPU-second is held to, below the quiet median on the doc's
// machine (236,000 on 2026-12-07 evening, after settled walls) because CI
// runs the guard on a busy host: CI runs of the code before read 0.6-1.0
// times its quiet figure. Half of it, 100,000, would still fail the code
// before settled walls on such a host (98,459 once). Update it with the doc.
constexpr double kStatedFeaturesPerCpuS = 200000.0;

double CpuSeconds() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return static_cast<double>(u.ru_utime.tv_sec + u.ru_stime.tv_sec) +
         1e-6 * static_cast<double>(u.ru_utime.tv_usec + u.ru_stime.tv_usec);
}

struct PoolScan {
  Vec2 sensor;
  std::vector<GroundFeature> features;
};

constexpr int kRobots = 8;  // the soak's

struct RunResult {
  bool ok = false;
  uint64_t added = 0;
  double cpu_s = 0.0;
  size_t published = 0;
  uint64_t digest = 0;
};

// One run of the workload in a fresh engine, timed in CPU seconds.
RunResult RunOnce(const std::vector<PoolScan>& pool, uint64_t target, bool soak_origin,
                  bool no_origin, const mapd::fusion::FusionParams& fusion) {
  RunResult result;
  const size_t n = pool.size();
  mapd::fusion::FusionEngine engine(fusion);
  std::mt19937_64 rng(1);
  std::normal_distribution<double> jitter(0.0, 0.01);
  uint64_t added = 0, observation = 0;
  std::vector<GroundFeature> features;
  // The whole loop is timed (a per-call getrusage would sum rounding errors);
  // the copy and jitter of each scan are a small part of it.
  const double c0 = CpuSeconds();
  for (size_t lap = 0; added < target; ++lap) {
    for (int robot = 0; robot < kRobots && added < target; ++robot) {
      const PoolScan& scan = pool[(lap + static_cast<size_t>(robot) * n / kRobots) % n];
      // As the soak: the jitter moves the whole scan, features and sensor.
      const Vec2 shift(jitter(rng), jitter(rng));
      features = scan.features;
      ++observation;
      for (size_t k = 0; k < features.size(); ++k) {
        features[k].id = (observation << 10) | k;
        features[k].segment.a += shift;
        features[k].segment.b += shift;
      }
      const Vec2 sensor = soak_origin ? shift : Vec2(scan.sensor + shift);
      const auto robot_id = static_cast<mapd::fusion::RobotId>(robot);
      const mapd::Status s = no_origin ? engine.Add(observation, robot_id, features)
                                       : engine.AddFrom(observation, robot_id, sensor, features);
      if (!s.ok()) {
        std::fprintf(stderr, "fusion_cpu_guard: %s\n", s.ToString().c_str());
        return result;
      }
      added += features.size();
    }
  }
  const double cpu_s = CpuSeconds() - c0;
  // A digest of the published map (ids, support, members, endpoints' bits):
  // a speed-up must leave it as it was.
  uint64_t digest = 1469598103934665603ULL;
  const auto mix = [&](const void* p, size_t bytes) {
    for (size_t i = 0; i < bytes; ++i) {
      digest = (digest ^ static_cast<const unsigned char*>(p)[i]) * 1099511628211ULL;
    }
  };
  for (const mapd::fusion::FusedFeature& f : engine.Published()) {
    mix(&f.id, sizeof f.id);
    mix(&f.support, sizeof f.support);
    mix(&f.member_count, sizeof f.member_count);
    for (const Vec2& p : {f.segment.a, f.segment.b, f.fitted.a, f.fitted.b}) {
      mix(p.data(), 2 * sizeof(double));
    }
  }
  result.ok = true;
  result.added = added;
  result.cpu_s = cpu_s;
  result.published = engine.published_count();
  result.digest = digest;
  return result;
}

}  // namespace

int main(int argc, char** argv) {
  uint64_t target = 500'000;  // about 5 CPU s on the doc's machine
  bool soak_origin = false;
  bool no_origin = false;
  double min_ratio = 0.5;
  mapd::fusion::FusionParams fusion;  // the defaults: bounded, evidence on, retirement on
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--features" && i + 1 < argc) {
      target = std::strtoull(argv[++i], nullptr, 10);
    } else if (a == "--origin" && i + 1 < argc) {
      const std::string v = argv[++i];
      if (v != "pose" && v != "soak" && v != "none") {
        std::fprintf(stderr, "--origin pose|soak|none\n");
        return 2;
      }
      soak_origin = v == "soak";
      no_origin = v == "none";
    } else if (a == "--min-ratio" && i + 1 < argc) {
      min_ratio = std::atof(argv[++i]);
    } else if (a == "--retire-views" && i + 1 < argc) {
      fusion.retire_views = static_cast<uint32_t>(std::atoi(argv[++i]));  // 0: off
    } else if (a == "--refit-tolerance" && i + 1 < argc) {
      fusion.refit_tolerance_m = std::atof(argv[++i]);  // 0: every refit re-resolves
    } else {
      std::fprintf(stderr,
                   "usage: %s [--features N] [--origin pose|soak|none] [--min-ratio R] "
                   "[--retire-views N] [--refit-tolerance M]\n",
                   argv[0]);
      return 2;
    }
  }

  if (const mapd::Status valid = fusion.Validate(); !valid.ok()) {
    std::fprintf(stderr, "%s\n", valid.ToString().c_str());
    return 2;
  }

  // The soak's city pool (tests/bench/soak_bench.cc, CityPool), once: scans
  // are simulated outside the measurement.
  sc::ScenarioParams params;
  params.seed = 1;
  params.blocks_x = 4;
  params.blocks_y = 3;
  const sc::World world = sc::GenerateWorld(params);
  const sc::ScanSimulator sim(params, world);
  std::vector<PoolScan> pool;
  for (size_t k = 0; k < sim.size(); ++k) {
    sc::Scan scan = sim.Simulate(k);
    if (!scan.features.empty()) pool.push_back({scan.estimated_pose.t, std::move(scan.features)});
  }

  // CPU time still varies with what shares the host (a 2-core VM measured
  // 56,000-90,000 for the same build): the guard fails only if three runs in
  // a row are all below the bar, so one slow run is no alarm.
  constexpr int kAttempts = 3;
  for (int attempt = 1; attempt <= kAttempts; ++attempt) {
    const RunResult r = RunOnce(pool, target, soak_origin, no_origin, fusion);
    if (!r.ok) return 1;
    const double measured = static_cast<double>(r.added) / r.cpu_s;
    const double ratio = measured / kStatedFeaturesPerCpuS;
    std::printf(
        "fusion_cpu_guard: %llu raw features in %.2f CPU s, %zu published (digest %016llx); "
        "measured %.0f features/CPU-s, stated %.0f (docs/long-running.md), ratio %.2f (fails "
        "below %.2f; run %d of at most %d)\n",
        static_cast<unsigned long long>(r.added), r.cpu_s, r.published,
        static_cast<unsigned long long>(r.digest), measured, kStatedFeaturesPerCpuS, ratio,
        min_ratio, attempt, kAttempts);
    std::fflush(stdout);
    if (ratio >= min_ratio) return 0;
  }
  return 1;
}
