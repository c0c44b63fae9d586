// Axis-aligned boxes in metres (Eigen::AlignedBox3d), shared by ICP and
// occupancy fusion, which both clip work to where two maps can overlap.
#ifndef MAPD_VOXEL_ALIGNED_BOX_H_
#define MAPD_VOXEL_ALIGNED_BOX_H_

#include <Eigen/Geometry>

namespace mapd::voxel {

// The axis-aligned box holding `box` moved by T (its eight corners moved);
// empty for an empty box.
inline Eigen::AlignedBox3d TransformedBox(const Eigen::AlignedBox3d& box,
                                          const Eigen::Isometry3d& T) {
  Eigen::AlignedBox3d out;
  if (box.isEmpty()) return out;
  for (int corner = 0; corner < 8; ++corner) {
    out.extend(T * box.corner(static_cast<Eigen::AlignedBox3d::CornerType>(corner)));
  }
  return out;
}

}  // namespace mapd::voxel

#endif  // MAPD_VOXEL_ALIGNED_BOX_H_
