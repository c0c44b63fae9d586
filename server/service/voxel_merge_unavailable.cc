// MAPD_WITH_VOXEL=OFF: no voxel library (no PCL); MergeSubmaps is refused.
#include "service/voxel_merge.h"

namespace mapd::service {

bool VoxelMergeBuilt() { return false; }

StatusOr<voxel::MergeOutcome> MergeVoxelSubmaps(const std::vector<voxel::SubmapInput>&,
                                                const voxel::MergeParams&,
                                                const voxel::ProgressCallback&) {
  return Status::Unimplemented(
      "MergeSubmaps: this mapd was built without voxel merging (MAPD_WITH_VOXEL=OFF)");
}

StatusOr<std::vector<std::shared_ptr<voxel::PreparedSubmap>>> PrepareVoxelSubmaps(
    const std::vector<voxel::SubmapInput>&, const voxel::MergeParams&) {
  return Status::Unimplemented(
      "MergeSubmaps: this mapd was built without voxel merging (MAPD_WITH_VOXEL=OFF)");
}

StatusOr<voxel::MergeOutcome> MergePreparedVoxelSubmaps(
    const std::vector<std::shared_ptr<voxel::PreparedSubmap>>&, const voxel::MergeParams&,
    const voxel::ProgressCallback&) {
  return Status::Unimplemented(
      "MergeSubmaps: this mapd was built without voxel merging (MAPD_WITH_VOXEL=OFF)");
}

std::size_t PreparedVoxelSubmapBytes(const voxel::PreparedSubmap&) { return 0; }

StatusOr<voxel::GlobalMapBuild> ExtendVoxelGlobalMap(std::string_view,
                                                     const std::vector<voxel::PlacedSubmap>&,
                                                     const voxel::FusionParams&,
                                                     const std::atomic<bool>*) {
  return Status::Unimplemented(
      "no global map: this mapd was built without voxel merging (MAPD_WITH_VOXEL=OFF)");
}

}  // namespace mapd::service

namespace mapd::voxel {

// Never reached (no merge runs), but submap_merge.cc names them.
Status CheckMergeEvidence(const MergeOutcome&, const std::vector<double>&, const MergeParams&) {
  return Status::Unimplemented("this mapd was built without voxel merging (MAPD_WITH_VOXEL=OFF)");
}

MergeDecision DecideMerge(const StatusOr<MergeOutcome>& outcome, const std::vector<uint64_t>&,
                          const std::vector<double>&, const MergeParams&, bool) {
  MergeDecision refused;
  refused.reason = outcome.ok() ? Status::Unimplemented(
                                      "this mapd was built without voxel merging "
                                      "(MAPD_WITH_VOXEL=OFF)")
                                : outcome.status();
  return refused;
}

}  // namespace mapd::voxel
