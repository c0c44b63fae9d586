// Bounded against exact fusion (fusion/params.h, FusionMode): the same
// observations through both engines, in the same order, and the published maps
// compared feature by feature. Cases: the synthetic city (several seeds, clean
// and with pose noise; also driven three times round, as a fleet revisits a
// site) and the real CARMEN laser logs (shared/data/laser; skipped when absent).
// A markdown table on stdout, for docs/long-running.md.
//
//   fusion_modes_bench [--seeds N] [--data DIR] [--cover M] [--guard-rms M] [--floor-case N]
//   [--refit-tolerance M]
//   [--floor N [--exact]]
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <string>
#include <vector>

#include "bench/carmen.h"
#include "client/sim_robot.h"
#include "eval/metrics.h"
#include "fusion/engine.h"
#include "fusion/projection.h"
#include "service/ingest_batch.h"
#include "sim/city_scenario.h"

namespace mapd::bench {
namespace {

namespace sc = fusion::scenario;
using fusion::FusedFeature;
using fusion::FusionEngine;
using fusion::FusionMode;
using fusion::FusionParams;
using fusion::GroundFeature;
using geometry::Segment2;

struct Observation {
  fusion::ObservationId id;
  fusion::RobotId robot;
  std::vector<GroundFeature> features;
};

struct ModeRun {
  std::vector<FusedFeature> published;
  size_t nodes = 0;
  double cpu_s = 0;
};

double CpuNow() { return static_cast<double>(std::clock()) / CLOCKS_PER_SEC; }

ModeRun Run(const std::vector<Observation>& observations, FusionParams params, FusionMode mode) {
  params.mode = mode;
  FusionEngine engine(params);
  const double t0 = CpuNow();
  for (const Observation& o : observations) {
    const Status s = engine.Add(o.id, o.robot, o.features);
    if (!s.ok()) {
      std::fprintf(stderr, "observation %llu: %s\n", static_cast<unsigned long long>(o.id),
                   s.ToString().c_str());
      std::exit(1);
    }
  }
  ModeRun run;
  run.cpu_s = CpuNow() - t0;
  run.published = engine.Published();
  run.nodes = engine.node_count();
  return run;
}

// Largest endpoint distance of the better pairing (a-a/b-b or a-b/b-a), metres.
double SegmentGap(const Segment2& f, const Segment2& g) {
  return std::min(std::max((f.a - g.a).norm(), (f.b - g.b).norm()),
                  std::max((f.a - g.b).norm(), (f.b - g.a).norm()));
}

struct Comparison {
  size_t exact = 0, bounded = 0;
  size_t same_id = 0;               // bounded has a feature of the same id
  size_t within_1cm = 0;            // exact features with a bounded one within 1 cm (any id)
  double worst_m = 0;               // largest gap of an exact feature to its nearest bounded one
  size_t support_differs = 0;       // where the exact support is within the exact cap (32)
  size_t support_differs_high = 0;  // past it, where bounded support is a count (may overcount)
};

Comparison Compare(const std::vector<FusedFeature>& exact,
                   const std::vector<FusedFeature>& bounded) {
  Comparison c;
  c.exact = exact.size();
  c.bounded = bounded.size();
  for (const FusedFeature& e : exact) {
    // The bounded feature of the same id, else the nearest (two features can
    // share a segment after corner snapping, so nearest alone can mislead).
    double best = 1e300;
    const FusedFeature* match = nullptr;
    for (const FusedFeature& b : bounded) {
      const double gap = SegmentGap(e.segment, b.segment);
      if (b.id == e.id) {
        ++c.same_id;
        best = gap;
        match = &b;
        break;
      }
      if (gap < best) {
        best = gap;
        match = &b;
      }
    }
    c.within_1cm += best <= 0.01;
    c.worst_m = std::max(c.worst_m, best);
    if (match != nullptr && match->support != e.support) {
      ++(e.support <= 32 ? c.support_differs : c.support_differs_high);
    }
  }
  return c;
}

void PrintHeader() {
  std::printf(
      "| case | observations | raw features | exact: fused / nodes / CPU s | "
      "bounded: fused / nodes / CPU s | same id | within 1 cm | worst gap (m) | "
      "support differs (<= 32 / > 32) | walls found exact / bounded |\n");
  std::printf("|---|---|---|---|---|---|---|---|---|---|\n");
}

void PrintRow(const std::string& name, const std::vector<Observation>& observations,
              const ModeRun& exact, const ModeRun& bounded, const std::string& walls) {
  size_t raw = 0;
  for (const Observation& o : observations) raw += o.features.size();
  const Comparison c = Compare(exact.published, bounded.published);
  std::printf(
      "| %s | %zu | %zu | %zu / %zu / %.2f | %zu / %zu / %.2f | %zu | %zu | %.4f | %zu / %zu | %s "
      "|\n",
      name.c_str(), observations.size(), raw, c.exact, exact.nodes, exact.cpu_s, c.bounded,
      bounded.nodes, bounded.cpu_s, c.same_id, c.within_1cm, c.worst_m, c.support_differs,
      c.support_differs_high, walls.c_str());
  std::fflush(stdout);
}

void CityCases(int seeds, const FusionParams& params) {
  for (int seed = 1; seed <= seeds; ++seed) {
    for (int noisy = 0; noisy < 2; ++noisy) {
      sc::ScenarioParams sp;
      sp.seed = static_cast<uint64_t>(seed);
      if (noisy) {
        sp.pose_sigma_xy_m = 0.05;
        sp.pose_sigma_yaw_rad = 0.2 * 3.14159265358979323846 / 180.0;
      }
      const sc::World world = sc::GenerateWorld(sp);
      const sc::ScanSimulator sim(sp, world);
      std::vector<sc::Scan> scans;
      for (size_t k = 0; k < sim.size(); ++k) scans.push_back(sim.Simulate(k));
      for (int laps : {1, 3}) {
        // Lap l drives the same route again: the same scans with new ids and,
        // with pose noise, new pose errors (a different seed per lap).
        std::vector<Observation> observations;
        std::vector<sc::Scan> all_scans;
        for (int lap = 0; lap < laps; ++lap) {
          sc::ScenarioParams lap_params = sp;
          lap_params.seed = sp.seed + 1000 * static_cast<uint64_t>(lap);
          const sc::ScanSimulator lap_sim(lap_params, world);
          for (size_t k = 0; k < lap_sim.size(); ++k) {
            sc::Scan scan = lap == 0 ? scans[k] : lap_sim.Simulate(k);
            const uint64_t id = static_cast<uint64_t>(lap) * sim.size() + k + 1;
            for (GroundFeature& f : scan.features) f.id += (id - scan.observation) << 10;
            scan.observation = id;
            observations.push_back({id, 0, scan.features});
            all_scans.push_back(std::move(scan));
          }
        }
        const ModeRun exact = Run(observations, params, FusionMode::kExact);
        const ModeRun bounded = Run(observations, params, FusionMode::kBounded);
        const sc::MetricsParams mp;
        const sc::MapMetrics me = sc::Evaluate(world, all_scans, exact.published, mp);
        const sc::MapMetrics mb = sc::Evaluate(world, all_scans, bounded.published, mp);
        const std::string walls = std::to_string(me.walls_matched) + " / " +
                                  std::to_string(mb.walls_matched) + " of " +
                                  std::to_string(me.walls_seen);
        PrintRow("city seed " + std::to_string(seed) + (noisy ? ", pose noise" : ", clean") +
                     (laps > 1 ? ", " + std::to_string(laps) + " laps" : ""),
                 observations, exact, bounded, walls);
      }
    }
  }
}

void LaserCases(const std::string& data_dir, const FusionParams& params) {
  for (const LaserLogSpec& spec : LaserLogs()) {
    StatusOr<std::vector<LaserScan>> scans = ReadCarmenLaserLog(data_dir + "/" + spec.file);
    if (!scans.ok()) {
      std::printf("| %s | skipped: %s |\n", spec.name, scans.status().ToString().c_str());
      continue;
    }
    std::vector<Observation> observations;
    uint64_t next_id = 1;
    for (size_t s = 0; s < scans->size(); ++s) {
      Observation o{s + 1, 0, {}};
      for (const Segment2& line : ExtractLaserLines((*scans)[s], spec.max_range_m).lines) {
        GroundFeature f;
        f.id = next_id++;
        f.segment = line;
        o.features.push_back(f);
      }
      observations.push_back(std::move(o));
    }
    const ModeRun exact = Run(observations, params, FusionMode::kExact);
    const ModeRun bounded = Run(observations, params, FusionMode::kBounded);
    PrintRow(spec.name, observations, exact, bounded, "n/a");
  }
}

// The demo floor revisited: `robots` simulated robots (client/sim_robot.h)
// loop the floor; fn(observation id, ground features) per scan until `total`
// raw features.
template <typename Fn>
void FloorScans(const FusionParams& params, int robots, uint64_t total, Fn&& fn) {
  std::vector<client::SimRobot> sims;
  for (int r = 0; r < robots; ++r) {
    client::SimRobotParams p;
    p.robot_id = "r" + std::to_string(r);
    p.seed = static_cast<uint64_t>(r) + 1;
    p.start_fraction = static_cast<double>(r) / robots;
    sims.emplace_back(client::DefaultWorld(), p);
  }
  uint64_t fed = 0, observation = 0;
  service::IngestLimits limits;
  while (fed < total) {
    for (client::SimRobot& sim : sims) {
      StatusOr<service::IngestBatch> batch = service::ValidateBatch(sim.NextBatch(), limits);
      if (!batch.ok()) std::exit(1);
      ++observation;
      StatusOr<fusion::ProjectedObservation> projected = fusion::ProjectToGround(
          batch->features, geometry::Rigid3::Identity(), observation << 12, params);
      if (!projected.ok()) std::exit(1);
      fed += projected->ground.size();
      fn(observation, projected->ground);
    }
  }
}

// The floor as a comparison case: exact against bounded on the same scans.
void FloorCase(const FusionParams& params, uint64_t total) {
  std::vector<Observation> observations;
  FloorScans(params, 8, total, [&](uint64_t id, const std::vector<GroundFeature>& ground) {
    observations.push_back({id, 0, ground});
  });
  const ModeRun exact = Run(observations, params, FusionMode::kExact);
  const ModeRun bounded = Run(observations, params, FusionMode::kBounded);
  PrintRow("demo floor, 8 robots looping", observations, exact, bounded, "n/a");
}

// The floor fused by one engine until `total` raw features; prints per chunk
// of `report` features the fusion rate and the node count.
void FloorRevisit(const FusionParams& params, int robots, uint64_t total, uint64_t report) {
  FusionEngine engine(params);
  std::printf("\nDemo floor, %d robots, mode %s, cover_m %.3f:\n\n", robots,
              fusion::FusionModeName(params.mode), params.cover_m);
  std::printf("| raw features | nodes | fused | features/CPU-s (chunk) |\n|---|---|---|---|\n");
  uint64_t fed = 0, next_report = report, chunk_features = 0;
  double chunk_cpu = 0;
  FloorScans(params, robots, total, [&](uint64_t id, const std::vector<GroundFeature>& ground) {
    const double t0 = CpuNow();
    if (!engine.Add(id, 0, ground).ok()) std::exit(1);
    chunk_cpu += CpuNow() - t0;
    chunk_features += ground.size();
    fed += ground.size();
    if (fed < next_report) return;
    std::printf("| %llu | %zu | %zu | %.0f |\n", static_cast<unsigned long long>(fed),
                engine.node_count(), engine.published_count(),
                static_cast<double>(chunk_features) / std::max(chunk_cpu, 1e-9));
    std::fflush(stdout);
    chunk_cpu = 0;
    chunk_features = 0;
    next_report += report;
  });
}

}  // namespace
}  // namespace mapd::bench

int main(int argc, char** argv) {
  int seeds = 3;
  std::string data_dir = std::string(MAPD_SOURCE_DIR) + "/../shared/data/laser";
  mapd::fusion::FusionParams params;
  uint64_t floor_total = 0;
  uint64_t floor_case = 200000;  // raw features of the floor comparison case
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    const bool has_value = i + 1 < argc;
    if (a == "--seeds" && has_value) {
      seeds = std::atoi(argv[++i]);
    } else if (a == "--data" && has_value) {
      data_dir = argv[++i];
    } else if (a == "--cover" && has_value) {
      params.cover_m = std::atof(argv[++i]);
    } else if (a == "--floor" && has_value) {
      floor_total = std::strtoull(argv[++i], nullptr, 10);
    } else if (a == "--floor-case" && has_value) {
      floor_case = std::strtoull(argv[++i], nullptr, 10);
    } else if (a == "--exact") {
      params.mode = mapd::fusion::FusionMode::kExact;
    } else if (a == "--guard-rms" && has_value) {
      params.chain_max_rms_m = std::atof(argv[++i]);
    } else if (a == "--refit-tolerance" && has_value) {
      params.refit_tolerance_m = std::atof(argv[++i]);  // settled walls; 0: off
    } else {
      std::fprintf(stderr,
                   "usage: %s [--seeds N] [--data DIR] [--cover M] [--guard-rms M] [--floor-case "
                   "N] [--refit-tolerance M] [--floor N [--exact]]\n",
                   argv[0]);
      return 2;
    }
  }
  if (const mapd::Status s = params.Validate(); !s.ok()) {
    std::fprintf(stderr, "%s\n", s.ToString().c_str());
    return 2;
  }
  if (floor_total > 0) {
    mapd::bench::FloorRevisit(params, 8, floor_total, floor_total / 10);
    return 0;
  }
  std::printf(
      "cover_m = %.3f m, chain_max_rms_m = %.3f m, refit_tolerance_m = %.4f m; other parameters "
      "at their defaults\n\n",
      params.cover_m, params.chain_max_rms_m, params.refit_tolerance_m);
  mapd::bench::PrintHeader();
  if (seeds > 0) mapd::bench::CityCases(seeds, params);
  mapd::bench::LaserCases(data_dir, params);
  mapd::bench::FloorCase(params, floor_case);
  return 0;
}
