// MAPD_WITH_VOXEL=ON: merges run in the voxel library.
#include "service/voxel_merge.h"

namespace mapd::service {

bool VoxelMergeBuilt() { return true; }

StatusOr<voxel::MergeOutcome> MergeVoxelSubmaps(const std::vector<voxel::SubmapInput>& inputs,
                                                const voxel::MergeParams& params,
                                                const voxel::ProgressCallback& progress) {
  return voxel::MergeSubmaps(inputs, params, progress);
}

StatusOr<std::vector<std::shared_ptr<voxel::PreparedSubmap>>> PrepareVoxelSubmaps(
    const std::vector<voxel::SubmapInput>& inputs, const voxel::MergeParams& params) {
  return voxel::PrepareSubmaps(inputs, params);
}

StatusOr<voxel::MergeOutcome> MergePreparedVoxelSubmaps(
    const std::vector<std::shared_ptr<voxel::PreparedSubmap>>& inputs,
    const voxel::MergeParams& params, const voxel::ProgressCallback& progress) {
  return voxel::MergePreparedSubmaps(inputs, params, progress);
}

std::size_t PreparedVoxelSubmapBytes(const voxel::PreparedSubmap& view) {
  return view.MemoryBytes();
}

StatusOr<voxel::GlobalMapBuild> ExtendVoxelGlobalMap(
    std::string_view base_bt, const std::vector<voxel::PlacedSubmap>& members,
    const voxel::FusionParams& params, const std::atomic<bool>* stop) {
  return voxel::ExtendGlobalMap(base_bt, members, params, stop);
}

}  // namespace mapd::service
