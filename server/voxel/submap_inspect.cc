#include "voxel/octree_reader.h"

namespace mapd::voxel {

// Everything comes from the validating walk: no OctoMap tree and no voxel
// grid are built, so an upload's memory is its bytes, whatever they expand to.
StatusOr<SubmapSummary> InspectSubmap(std::string_view bytes, const OctreeReadLimits& limits) {
  StatusOr<OctreeSummary> tree = ValidateOctree(bytes, limits);
  if (!tree.ok()) return tree.status();
  SubmapSummary summary;
  summary.resolution = tree->resolution;
  summary.occupied_voxels = tree->occupied_voxels;
  summary.free_voxels = tree->free_voxels;
  if (tree->occupied_voxels > 0) {
    for (int a = 0; a < 3; ++a) {
      summary.bounds_min[a] = tree->occupied_min_key[a] * tree->resolution;
      summary.bounds_max[a] = (tree->occupied_max_key[a] + 1.0) * tree->resolution;
    }
  }
  return summary;
}

}  // namespace mapd::voxel
