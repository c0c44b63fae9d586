// The occupied voxels of an OctoMap file (.bt or .ot), for rendering. A file
// from disk or from the server is not trusted either: it goes through the
// server's safe parser (server/voxel/octree_reader.h) and voxel grid view.
// That library needs OctoMap, so it is linked only when mapd is configured
// with MAPD_WITH_VOXEL; without it LoadOccupiedVoxels answers Unimplemented.
#ifndef MAPD_CLIENT_VOXEL_LOADER_H_
#define MAPD_CLIENT_VOXEL_LOADER_H_

#include <string>
#include <string_view>
#include <vector>

#include "client/rigid_transform.h"
#include "common/status.h"

namespace mapd::client {

// The message of the Unimplemented status when voxel support is not built.
inline constexpr char kNoVoxelSupport[] = "mapctl built without voxel support";

struct LoadedVoxels {
  double resolution_m = 0;          // voxel edge
  std::vector<Point3> centres_m;    // occupied voxels at the finest resolution, file frame
};

// False when mapctl was built without MAPD_WITH_VOXEL.
bool VoxelSupportBuilt();

// InvalidArgument for a malformed file, ResourceExhausted beyond the reader's
// limits (the server's defaults), Unimplemented without voxel support.
StatusOr<LoadedVoxels> LoadOccupiedVoxels(std::string_view bytes);

}  // namespace mapd::client

#endif  // MAPD_CLIENT_VOXEL_LOADER_H_
