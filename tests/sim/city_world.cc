#include "sim/city_world.h"

#include <cmath>
#include <random>
#include <utility>

namespace mapd::sim {

Eigen::Vector3d Ramp::normal() const {
  const Eigen::Vector2d along = end - start;
  const double slope = rise_m / along.norm();
  const Eigen::Vector2d a = along.normalized();
  return Eigen::Vector3d(-slope * a.x(), -slope * a.y(), 1.0).normalized();
}

double Ramp::offset() const { return -normal().dot(Eigen::Vector3d(start.x(), start.y(), 0.0)); }

CityWorld::CityWorld(const fusion::scenario::World& world, const CityHeights& heights,
                     std::vector<Ramp> ramps)
    : world_(world), ramps_(std::move(ramps)) {
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
  for (size_t k = 0; k < ramps_.size(); ++k) {
    const Ramp& r = ramps_[k];
    const Eigen::Vector3d n = r.normal();
    const double along_dir = n.dot(direction);
    if (std::abs(along_dir) < 1e-12) continue;
    const double t = -(n.dot(origin) + r.offset()) / along_dir;
    if (t <= 1e-9 || t >= best.range_m) continue;
    const Eigen::Vector2d q = (origin + t * direction).head<2>() - r.start;
    const Eigen::Vector2d a = (r.end - r.start).normalized();
    const double u = q.dot(a);
    const double v = q.x() * a.y() - q.y() * a.x();
    if (u < 0.0 || u > (r.end - r.start).norm() || std::abs(v) > 0.5 * r.width_m) continue;
    best = {t, -10 - static_cast<int>(k)};
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
