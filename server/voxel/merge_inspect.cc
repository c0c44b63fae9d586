#include <octomap/OcTree.h>

#include "voxel/merge.h"
#include "voxel/octree_reader.h"
#include "voxel/voxel_grid.h"

namespace mapd::voxel {

StatusOr<SubmapSummary> InspectSubmap(std::string_view bytes) {
  auto tree = ReadOctree(bytes);
  if (!tree.ok()) return tree.status();
  auto grid = VoxelGrid::FromOcTree(**tree);
  if (!grid.ok()) return grid.status();
  SubmapSummary summary;
  summary.resolution = grid->resolution();
  summary.occupied_voxels = grid->num_occupied();
  const int depth = static_cast<int>((*tree)->getTreeDepth());
  for (auto it = (*tree)->begin_leafs(), end = (*tree)->end_leafs(); it != end; ++it) {
    if ((*tree)->isNodeOccupied(*it)) continue;
    summary.free_voxels += uint64_t{1} << (3 * (depth - static_cast<int>(it.getDepth())));
  }
  if (!grid->empty()) {
    summary.bounds_min = grid->min_corner();
    summary.bounds_max = grid->max_corner();
  }
  return summary;
}

}  // namespace mapd::voxel
