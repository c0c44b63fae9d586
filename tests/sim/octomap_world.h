// A real OctoMap map as a LidarWorld (rays stop at the first occupied voxel,
// found by octomap::OcTree::castRay; unknown space is passed through), and
// sensor poses sampled in its known-free space.
#ifndef MAPD_TESTS_SIM_OCTOMAP_WORLD_H_
#define MAPD_TESTS_SIM_OCTOMAP_WORLD_H_

#include <octomap/OcTree.h>

#include <cstdint>
#include <vector>

#include "geometry/rigid3.h"
#include "sim/lidar_sim.h"

namespace mapd::sim {

class OctoMapWorld : public LidarWorld {
 public:
  // Keeps a reference to `tree`, which must outlive this object. Label 0 for a hit.
  explicit OctoMapWorld(const octomap::OcTree& tree) : tree_(tree) {}
  // The range is to where the ray enters the hit voxel (not its centre).
  RayHit Cast(const Eigen::Vector3d& origin, const Eigen::Vector3d& direction,
              double max_range_m) const override;

 private:
  const octomap::OcTree& tree_;
};

struct PoseSamplingParams {
  size_t count = 80;
  // Height above the floor: the first occupied voxel straight below must lie
  // within floor_tolerance_m of the floor level (EstimateFloorZ), so poses
  // stand on the floor, not on furniture or over a roofless room's walls.
  double min_height_m = 0.9;
  double max_height_m = 1.6;
  double floor_tolerance_m = 0.2;
  // Inside the building: of 8 horizontal rays at least this many hit within 20 m.
  int min_enclosing_rays = 6;
  double clearance_m = 0.4;    // no occupied or unknown voxel this close (6 directions)
  double min_spacing_m = 1.0;  // between accepted poses
  uint64_t seed = 1;
};

// The floor level: the most occupied horizontal layer (one voxel thick) of the
// lower half of the map.
double EstimateFloorZ(const octomap::OcTree& tree);

// Up to params.count poses at known-free voxel centres with a floor below
// them, random yaw, ordered into a route by nearest-neighbour from the first
// (the route is not collision-checked between poses: each scan stands alone).
std::vector<geometry::Rigid3> SampleFreePoses(const octomap::OcTree& tree,
                                              const PoseSamplingParams& params);

}  // namespace mapd::sim

#endif  // MAPD_TESTS_SIM_OCTOMAP_WORLD_H_
