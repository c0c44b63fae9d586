#include "voxel/merge_overlap.h"

namespace mapd::voxel {
namespace {

bool OccupiedNear(const VoxelGrid& grid, const VoxelKey& key) {
  if (grid.IsOccupied(key)) return true;
  for (int dx = -1; dx <= 1; ++dx) {
    for (int dy = -1; dy <= 1; ++dy) {
      for (int dz = -1; dz <= 1; ++dz) {
        if ((dx | dy | dz) == 0) continue;
        if (grid.IsOccupied(key + VoxelKey(dx, dy, dz))) return true;
      }
    }
  }
  return false;
}

}  // namespace

OverlapScore ComputeOverlapScore(const VoxelGrid& a, const VoxelGrid& b,
                                 const Eigen::Isometry3d& T_a_b, std::size_t max_points) {
  OverlapScore out;
  const auto& centres = b.occupied_centres();
  if (centres.empty() || a.empty()) return out;
  std::size_t step = 1;
  if (max_points > 0 && centres.size() > max_points)
    step = (centres.size() + max_points - 1) / max_points;
  for (std::size_t i = 0; i < centres.size(); i += step) {
    const VoxelKey key = a.PointToKey(T_a_b * centres[i]);
    if (OccupiedNear(a, key)) {
      ++out.observed;
      ++out.coinciding;
    } else if (a.State(key) != VoxelState::kUnknown) {
      ++out.observed;
    }
  }
  if (out.observed > 0)
    out.score = static_cast<double>(out.coinciding) / static_cast<double>(out.observed);
  return out;
}

}  // namespace mapd::voxel
