#include "sim/city_world.h"

#include <random>

namespace mapd::sim {

CityWorld::CityWorld(const fusion::scenario::World& world, const CityHeights& heights)
    : world_(world) {
  std::mt19937_64 rng(heights.seed);
  std::uniform_real_distribution<double> wall(heights.wall_min_m, heights.wall_max_m);
  std::vector<double> building(world.buildings.size());
  for (double& h : building) h = wall(rng);
  heights_.reserve(world.structures.size());
  for (const auto& s : world.structures) {
    heights_.push_back(s.kind == fusion::scenario::StructureKind::kWall && s.building >= 0
                           ? building[static_cast<size_t>(s.building)]
                           : heights.trivial_m);
  }
}

RayHit CityWorld::Cast(const Eigen::Vector3d& origin, const Eigen::Vector3d& direction,
                       double max_range_m) const {
  RayHit best;
  best.range_m = max_range_m;
  if (direction.z() < -1e-9) {
    const double t = -origin.z() / direction.z();
    if (t > 0 && t <= best.range_m) best = {t, -1};
  }
  // Brute force over the structures (a few hundred): a scan costs milliseconds.
  const Eigen::Vector2d o = origin.head<2>();
  const Eigen::Vector2d d = direction.head<2>();
  for (size_t i = 0; i < world_.structures.size(); ++i) {
    const auto& seg = world_.structures[i].segment;
    const Eigen::Vector2d e = seg.b - seg.a;
    const double denom = d.x() * e.y() - d.y() * e.x();
    if (std::abs(denom) < 1e-12) continue;
    const Eigen::Vector2d w = seg.a - o;
    const double t = (w.x() * e.y() - w.y() * e.x()) / denom;  // along the ray
    const double u = (w.x() * d.y() - w.y() * d.x()) / denom;  // along the segment
    if (t <= 1e-9 || t >= best.range_m || u < 0.0 || u > 1.0) continue;
    const double z = origin.z() + t * direction.z();
    if (z < 0.0 || z > heights_[i]) continue;
    best = {t, static_cast<int>(i)};
  }
  return best;
}

}  // namespace mapd::sim
