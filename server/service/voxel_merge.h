// The one place where mapd's build decides whether it can merge voxel
// submaps. CMake compiles voxel_merge.cc (MAPD_WITH_VOXEL=ON: the voxel
// library, with PCL) or voxel_merge_unavailable.cc (OFF); nothing else in the
// service depends on the choice. Uploads, listing, fetching and deleting
// submaps need only voxel_io and work in both builds.
#ifndef MAPD_SERVICE_VOXEL_MERGE_H_
#define MAPD_SERVICE_VOXEL_MERGE_H_

#include <atomic>
#include <cstddef>
#include <memory>
#include <string_view>
#include <vector>

#include "common/status.h"
#include "voxel/global_map.h"  // types only, as merge.h
#include "voxel/merge.h"       // types only; the functions live in the voxel library

namespace mapd::service {

// True when this mapd can merge (the voxel library is linked).
bool VoxelMergeBuilt();

// voxel::MergeSubmaps, or Unimplemented without the voxel library.
StatusOr<voxel::MergeOutcome> MergeVoxelSubmaps(const std::vector<voxel::SubmapInput>& inputs,
                                                const voxel::MergeParams& params,
                                                const voxel::ProgressCallback& progress);

// voxel::PrepareSubmaps, or Unimplemented without the voxel library.
StatusOr<std::vector<std::shared_ptr<voxel::PreparedSubmap>>> PrepareVoxelSubmaps(
    const std::vector<voxel::SubmapInput>& inputs, const voxel::MergeParams& params);

// voxel::MergePreparedSubmaps, or Unimplemented without the voxel library.
StatusOr<voxel::MergeOutcome> MergePreparedVoxelSubmaps(
    const std::vector<std::shared_ptr<voxel::PreparedSubmap>>& inputs,
    const voxel::MergeParams& params, const voxel::ProgressCallback& progress);

// voxel::PreparedSubmap::MemoryBytes (0 without the voxel library: there are no views).
std::size_t PreparedVoxelSubmapBytes(const voxel::PreparedSubmap& view);

// voxel::ExtendGlobalMap, or Unimplemented without the voxel library.
StatusOr<voxel::GlobalMapBuild> ExtendVoxelGlobalMap(
    std::string_view base_bt, const std::vector<voxel::PlacedSubmap>& members,
    const voxel::FusionParams& params, const std::atomic<bool>* stop);

}  // namespace mapd::service

#endif  // MAPD_SERVICE_VOXEL_MERGE_H_
