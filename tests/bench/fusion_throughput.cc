// Throughput sanity check of FusionEngine::Add (not a test): feeds ~200,000
// synthetic noisy wall features in observations of 20 and prints features/s.
// Target: >= 100,000 features/s single-threaded in a Release build.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <random>
#include <vector>

#include "fusion/engine.h"

namespace {

using mapd::fusion::FusionEngine;
using mapd::fusion::GroundFeature;
using mapd::geometry::Segment2;
using mapd::geometry::Vec2;

}  // namespace

int main(int argc, char** argv) {
  const int feature_target = argc > 1 ? std::atoi(argv[1]) : 200000;
  constexpr int kPerObservation = 20;
  constexpr int kBlocks = 24;         // kBlocks x kBlocks buildings
  constexpr double kSpacingM = 25.0;  // block pitch

  std::mt19937 rng(42);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::normal_distribution<double> noise(0.0, 0.02);
  const auto uniform = [&](double lo, double hi) { return lo + (hi - lo) * unit(rng); };

  // One slightly rotated rectangular building per block: 4 walls each.
  std::vector<Segment2> walls;
  for (int i = 0; i < kBlocks; ++i) {
    for (int j = 0; j < kBlocks; ++j) {
      // One draw per statement: the order of a call's arguments is unspecified,
      // and the block world must be the same with every compiler.
      const double dx = uniform(0, 3);
      const double dy = uniform(0, 3);
      const Vec2 origin(i * kSpacingM + dx, j * kSpacingM + dy);
      const double yaw = uniform(-0.3, 0.3);
      const Vec2 ex(std::cos(yaw), std::sin(yaw)), ey(-ex.y(), ex.x());
      const double w = uniform(8, 18), h = uniform(8, 18);
      const Vec2 c[4] = {origin, origin + w * ex, origin + w * ex + h * ey, origin + h * ey};
      for (int k = 0; k < 4; ++k) walls.push_back({c[k], c[(k + 1) % 4]});
    }
  }

  // Observations: a robot near block (i, j) sees partial views of the walls of
  // that block and its neighbours.
  std::vector<std::vector<GroundFeature>> observations;
  uint64_t next_id = 1;
  for (int total = 0; total < feature_target; total += kPerObservation) {
    const int bi = static_cast<int>(rng() % kBlocks), bj = static_cast<int>(rng() % kBlocks);
    std::vector<GroundFeature> features;
    while (static_cast<int>(features.size()) < kPerObservation) {
      const int i = std::clamp(bi + static_cast<int>(rng() % 3) - 1, 0, kBlocks - 1);
      const int j = std::clamp(bj + static_cast<int>(rng() % 3) - 1, 0, kBlocks - 1);
      const Segment2& wall = walls[static_cast<size_t>((i * kBlocks + j) * 4 + rng() % 4)];
      const double t0 = uniform(-0.02, 0.5), t1 = std::min(1.02, t0 + uniform(0.2, 0.7));
      GroundFeature f;
      f.id = next_id++;
      const double ax = noise(rng);
      const double ay = noise(rng);
      const double bx = noise(rng);
      const double by = noise(rng);
      f.segment = {wall.a + t0 * wall.direction() + Vec2(ax, ay),
                   wall.a + t1 * wall.direction() + Vec2(bx, by)};
      f.z_max_m = 3.0;
      features.push_back(f);
    }
    observations.push_back(std::move(features));
  }

  FusionEngine engine{mapd::fusion::FusionParams()};
  const auto start = std::chrono::steady_clock::now();
  for (size_t o = 0; o < observations.size(); ++o) {
    mapd::fusion::ChangeFeed feed;
    const mapd::Status s = engine.Add(o + 1, o % 5, observations[o], &feed);
    if (!s.ok()) {
      std::fprintf(stderr, "%s\n", s.ToString().c_str());
      return 1;
    }
  }
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::printf("%zu features in %zu observations: %.3f s, %.0f features/s\n", engine.feature_count(),
              observations.size(), seconds, static_cast<double>(engine.feature_count()) / seconds);
  std::printf("%zu clusters, %zu published (%zu walls)\n", engine.cluster_count(),
              engine.published_count(), walls.size());
  return 0;
}
