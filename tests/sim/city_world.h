// The synthetic city of fusion/scenario (2D building outlines, fences, poles)
// as a 3D LidarWorld: every structure is extruded from the ground plane z = 0
// to a height, and the ground is an infinite plane. Labels: the structure
// index (World::structures), -1 for the ground.
#ifndef MAPD_TESTS_SIM_CITY_WORLD_H_
#define MAPD_TESTS_SIM_CITY_WORLD_H_

#include <vector>

#include "fusion/scenario/scenario.h"
#include "sim/lidar_sim.h"

namespace mapd::sim {

struct CityHeights {
  double wall_min_m = 6.0;   // building heights are drawn per building in [min, max]
  double wall_max_m = 20.0;
  double trivial_m = 2.0;    // fences and poles
  uint64_t seed = 1;
};

class CityWorld : public LidarWorld {
 public:
  // Keeps a reference to `world`, which must outlive this object.
  CityWorld(const fusion::scenario::World& world, const CityHeights& heights);
  RayHit Cast(const Eigen::Vector3d& origin, const Eigen::Vector3d& direction,
              double max_range_m) const override;
  double height(size_t structure) const { return heights_[structure]; }

 private:
  const fusion::scenario::World& world_;
  std::vector<double> heights_;  // per structure, metres
};

}  // namespace mapd::sim

#endif  // MAPD_TESTS_SIM_CITY_WORLD_H_
