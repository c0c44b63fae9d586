// The synthetic city of sim/city_scenario.h (2D building outlines, fences, poles)
// as a 3D LidarWorld: every structure is extruded from the ground plane z = 0
// to a height, and the ground is an infinite plane. Labels: the structure
// index (World::structures), -1 for the ground, -10 - k for ramp k.
#ifndef MAPD_TESTS_SIM_CITY_WORLD_H_
#define MAPD_TESTS_SIM_CITY_WORLD_H_

#include <vector>

#include "sim/city_scenario.h"
#include "sim/lidar_sim.h"

namespace mapd::sim {

struct CityHeights {
  double wall_min_m = 6.0;  // building heights are drawn per building in [min, max]
  double wall_max_m = 20.0;
  double trivial_m = 2.0;  // fences and poles
  uint64_t seed = 1;
};

// A sloped plate: a rectangle that rises from the ground at `start` to rise_m
// at `end` (map frame, metres), width_m across. Seen from above only (it never
// rises above the sensor).
struct Ramp {
  Eigen::Vector2d start = Eigen::Vector2d::Zero();
  Eigen::Vector2d end = Eigen::Vector2d::UnitX();
  double width_m = 4.0;
  double rise_m = 1.0;
  // Its plane n.x + d = 0, n upward unit.
  Eigen::Vector3d normal() const;
  double offset() const;
};

class CityWorld : public LidarWorld {
 public:
  // Keeps a reference to `world`, which must outlive this object.
  CityWorld(const fusion::scenario::World& world, const CityHeights& heights,
            std::vector<Ramp> ramps = {});
  RayHit Cast(const Eigen::Vector3d& origin, const Eigen::Vector3d& direction,
              double max_range_m) const override;
  double height(size_t structure) const { return heights_[structure]; }

 private:
  const fusion::scenario::World& world_;
  std::vector<double> heights_;  // per structure, metres
  std::vector<Ramp> ramps_;
};

}  // namespace mapd::sim

#endif  // MAPD_TESTS_SIM_CITY_WORLD_H_
