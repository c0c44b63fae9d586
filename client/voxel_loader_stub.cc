// LoadOccupiedVoxels without the voxel library (MAPD_WITH_VOXEL=OFF).
#include "client/voxel_loader.h"

namespace mapd::client {

bool VoxelSupportBuilt() { return false; }

StatusOr<LoadedVoxels> LoadOccupiedVoxels(std::string_view /*bytes*/) {
  return Status::Unimplemented(kNoVoxelSupport);
}

}  // namespace mapd::client
