// Adversarial workloads for FusionEngine (issue 46): what one robot's valid
// but hostile input costs the fuser, next to the revisited floor a normal
// fleet sends. A benchmark, not a test: run it by hand, figures go to
// docs/reliability.md ("Fusion cost per observation").
//
//   fusion_adversarial_bench [--workload NAME] [--observations N] [--cpu-budget S]
//                            [--max-component-nodes N]
//
// Each workload feeds observations through AddFrom (with a sensor origin, as
// mapd does) until N observations or S CPU-seconds, whichever comes first, and
// prints fused features per CPU-second overall, for the first and the last
// tenth of the run (a rate that falls with history is a cost that grows
// with it), and the slowest single observation.
#include <time.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <functional>
#include <random>
#include <string>
#include <vector>

#include "fusion/engine.h"

namespace {

using mapd::fusion::FusionEngine;
using mapd::fusion::GroundFeature;
using mapd::geometry::Segment2;
using mapd::geometry::Vec2;

double CpuNow() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

struct Observation {
  Vec2 sensor_xy_m;
  std::vector<Segment2> segments;
};

// Makes observation k of a workload.
using Generator = std::function<Observation(std::mt19937&, int k)>;

struct Workload {
  const char* name;
  const char* what;
  Generator next;
};

constexpr double kRoomW = 10.0, kRoomH = 8.0;

// The four walls of a 10 x 8 m room seen from inside, 2 cm noise: what a
// robot looping a small floor sends.
void AddRoom(std::mt19937& rng, std::vector<Segment2>* out) {
  std::normal_distribution<double> noise(0.0, 0.02);
  const Vec2 c[4] = {{0, 0}, {kRoomW, 0}, {kRoomW, kRoomH}, {0, kRoomH}};
  for (int i = 0; i < 4; ++i) {
    const Vec2 a = c[i], b = c[(i + 1) % 4];
    const double ax = noise(rng), ay = noise(rng), bx = noise(rng), by = noise(rng);
    out->push_back({a + 0.1 * (b - a) + Vec2(ax, ay), a + 0.9 * (b - a) + Vec2(bx, by)});
  }
}

Vec2 RoomCentre() { return {kRoomW / 2, kRoomH / 2}; }

std::vector<Workload> Workloads() {
  std::vector<Workload> w;
  w.push_back({"floor", "the 10 x 8 m room, revisited (the reference)", [](std::mt19937& rng, int) {
                 Observation o{RoomCentre(), {}};
                 AddRoom(rng, &o.segments);
                 return o;
               }});
  w.push_back({"junk", "the room plus 4 random axis-aligned 2 m walls in 100 x 100 m",
               [](std::mt19937& rng, int) {
                 std::uniform_real_distribution<double> pos(-45.0, 55.0);
                 Observation o{RoomCentre(), {}};
                 AddRoom(rng, &o.segments);
                 for (int i = 0; i < 4; ++i) {
                   const Vec2 a(pos(rng), pos(rng));
                   o.segments.push_back({a, a + (rng() % 2 ? Vec2(2, 0) : Vec2(0, 2))});
                 }
                 return o;
               }});
  w.push_back({"random", "8 random segments, any angle, 0.1-100 m long, in 200 x 200 m",
               [](std::mt19937& rng, int) {
                 std::uniform_real_distribution<double> pos(-100.0, 100.0), angle(0.0, 6.2832);
                 std::uniform_real_distribution<double> log_len(std::log(0.1), std::log(100.0));
                 Observation o{{pos(rng), pos(rng)}, {}};
                 for (int i = 0; i < 8; ++i) {
                   const Vec2 a(pos(rng), pos(rng));
                   const double t = angle(rng), len = std::exp(log_len(rng));
                   o.segments.push_back({a, a + len * Vec2(std::cos(t), std::sin(t))});
                 }
                 return o;
               }});
  w.push_back(
      {"same_wall", "one 5 m wall, identical, 8 times per observation", [](std::mt19937&, int) {
         Observation o{{0, -3}, {}};
         for (int i = 0; i < 8; ++i) o.segments.push_back({{-2.5, 0}, {2.5, 0}});
         return o;
       }});
  w.push_back({"limits", "the room moved to the corner of the coordinate range (+-1e6 m)",
               [](std::mt19937& rng, int k) {
                 const Vec2 corner = (k % 2 ? 1.0 : -1.0) * Vec2(999980.0, 999980.0);
                 Observation o{corner + RoomCentre(), {}};
                 AddRoom(rng, &o.segments);
                 for (Segment2& s : o.segments) s = {s.a + corner, s.b + corner};
                 return o;
               }});
  w.push_back({"far_sight",
               "the room plus one 20 m wall 1e6 m from the sensor (longest sight line)",
               [](std::mt19937& rng, int) {
                 std::uniform_real_distribution<double> along(-1e5, 1e5);
                 Observation o{RoomCentre(), {}};
                 AddRoom(rng, &o.segments);
                 const double x = along(rng);
                 o.segments.push_back({{x, 999000.0}, {x + 20.0, 999000.0}});
                 return o;
               }});
  return w;
}

struct Result {
  int observations = 0;
  double features = 0;
  double cpu_s = 0;
  double first_rate = 0, last_rate = 0;
  double worst_ms = 0;
  size_t published = 0, nodes = 0;
};

Result Run(const Workload& w, int max_observations, double cpu_budget_s,
           const mapd::fusion::FusionParams& params) {
  FusionEngine engine{params};
  std::mt19937 rng(46);
  uint64_t next_id = 1;
  Result r;
  std::vector<double> per_obs_cpu;
  std::vector<size_t> per_obs_features;
  const double start = CpuNow();
  for (int k = 0; k < max_observations; ++k) {
    const Observation o = w.next(rng, k);
    std::vector<GroundFeature> features;
    for (const Segment2& s : o.segments) {
      GroundFeature f;
      f.id = next_id++;
      f.segment = s;
      f.z_max_m = 2.5;
      features.push_back(f);
    }
    const double t0 = CpuNow();
    const mapd::Status s =
        engine.AddFrom(static_cast<uint64_t>(k) + 1, 1 + k % 4, o.sensor_xy_m, features);
    const double dt = CpuNow() - t0;
    if (!s.ok()) {
      std::fprintf(stderr, "%s: observation %d refused: %s\n", w.name, k, s.ToString().c_str());
      std::exit(1);
    }
    per_obs_cpu.push_back(dt);
    per_obs_features.push_back(features.size());
    r.worst_ms = std::max(r.worst_ms, 1e3 * dt);
    if (CpuNow() - start > cpu_budget_s) break;
  }
  r.observations = static_cast<int>(per_obs_cpu.size());
  const auto rate = [&](size_t from, size_t to) {
    double cpu = 0, n = 0;
    for (size_t i = from; i < to; ++i) cpu += per_obs_cpu[i], n += per_obs_features[i];
    return cpu > 0 ? n / cpu : 0.0;
  };
  const size_t n = per_obs_cpu.size(), tenth = std::max<size_t>(1, n / 10);
  for (size_t i = 0; i < n; ++i) r.cpu_s += per_obs_cpu[i], r.features += per_obs_features[i];
  r.first_rate = rate(0, tenth);
  r.last_rate = rate(n - tenth, n);
  r.published = engine.published_count();
  r.nodes = engine.node_count();
  return r;
}

}  // namespace

int main(int argc, char** argv) {
  std::string only;
  int max_observations = 100000;
  double cpu_budget_s = 20.0;
  mapd::fusion::FusionParams params;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--workload" && i + 1 < argc) {
      only = argv[++i];
    } else if (arg == "--observations" && i + 1 < argc) {
      max_observations = std::atoi(argv[++i]);
    } else if (arg == "--max-component-nodes" && i + 1 < argc) {
      params.max_component_nodes = static_cast<uint32_t>(std::atoi(argv[++i]));
    } else if (arg == "--cpu-budget" && i + 1 < argc) {
      cpu_budget_s = std::atof(argv[++i]);
    } else {
      std::fprintf(stderr,
                   "usage: fusion_adversarial_bench [--workload NAME] [--observations N] "
                   "[--cpu-budget S] [--max-component-nodes N]\n");
      return 2;
    }
  }
  std::printf(
      "| workload | observations | features | CPU s | fused/CPU-s | first 10 %% | last 10 %% "
      "| slowest obs ms | representatives | published |\n");
  std::printf("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n");
  bool found = false;
  for (const Workload& w : Workloads()) {
    if (!only.empty() && only != w.name) continue;
    found = true;
    const Result r = Run(w, max_observations, cpu_budget_s, params);
    std::printf("| %s | %d | %.0f | %.2f | %.0f | %.0f | %.0f | %.2f | %zu | %zu |\n", w.name,
                r.observations, r.features, r.cpu_s, r.features / r.cpu_s, r.first_rate,
                r.last_rate, r.worst_ms, r.nodes, r.published);
    std::fflush(stdout);
  }
  if (!found) {
    std::fprintf(stderr, "no workload named %s\n", only.c_str());
    return 2;
  }
  return 0;
}
