// The occupied voxels of an OctoMap file (.bt or .ot), for rendering. A file
// from disk or from the server is not trusted either: it goes through the
// server's safe parser and voxel grid view (voxel_io: server/voxel/octree_reader.h).
#ifndef MAPD_CLIENT_VOXEL_LOADER_H_
#define MAPD_CLIENT_VOXEL_LOADER_H_

#include <string>
#include <string_view>
#include <vector>

#include "common/status.h"
#include "geometry/rigid3.h"
#include "voxel/voxel_grid.h"

namespace mapd::client {

struct LoadedVoxels {
  double resolution_m = 0;                 // voxel edge
  std::vector<Eigen::Vector3d> centres_m;  // occupied voxels at the finest resolution, file frame
};

// InvalidArgument for a malformed file, ResourceExhausted beyond the reader's
// limits (the server's defaults).
StatusOr<LoadedVoxels> LoadOccupiedVoxels(std::string_view bytes);
// The whole grid view (occupied, free and unknown), with the same checks.
StatusOr<voxel::VoxelGrid> LoadVoxelGrid(std::string_view bytes);

}  // namespace mapd::client

#endif  // MAPD_CLIENT_VOXEL_LOADER_H_
