// A 3D corner of a voxel submap: where three planar faces meet
// (grid-map-fusion paper, Qiu et al., sections III-IV; docs/algorithms.md
// part B).
// Produced by corner extraction, consumed by corner matching.
#ifndef MAPD_VOXEL_CORNER_H_
#define MAPD_VOXEL_CORNER_H_

#include <Eigen/Core>
#include <array>
#include <vector>

namespace mapd::voxel {

struct Corner {
  Eigen::Vector3d position = Eigen::Vector3d::Zero();  // metres, the submap's frame
  // Unit normals of the three planes that meet here (oriented away from the
  // occupied side where that is known). Rigid motions rotate them with the map.
  std::array<Eigen::Vector3d, 3> normals{Eigen::Vector3d::UnitX(), Eigen::Vector3d::UnitY(),
                                         Eigen::Vector3d::UnitZ()};
  int support = 0;  // corner candidates clustered into this corner
};

using CornerSet = std::vector<Corner>;

}  // namespace mapd::voxel

#endif  // MAPD_VOXEL_CORNER_H_
