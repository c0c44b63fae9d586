// MAPD_WITH_VOXEL=ON: merges run in the voxel library.
#include "service/voxel_merge.h"

namespace mapd::service {

bool VoxelMergeBuilt() { return true; }

StatusOr<voxel::MergeOutcome> MergeVoxelSubmaps(const std::vector<voxel::SubmapInput>& inputs,
                                                const voxel::MergeParams& params,
                                                const voxel::ProgressCallback& progress) {
  return voxel::MergeSubmaps(inputs, params, progress);
}

}  // namespace mapd::service
