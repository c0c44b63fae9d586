// Internal to corner extraction: the sliding-window candidate test (B.1).
#ifndef MAPD_VOXEL_CORNER_WINDOW_H_
#define MAPD_VOXEL_CORNER_WINDOW_H_

#include <cstddef>
#include <vector>

#include "common/status.h"
#include "voxel/voxel_grid.h"

namespace mapd::voxel::internal {

struct WindowCandidates {
  std::vector<VoxelKey> keys;  // occupied voxels that passed the 26-shift test
  std::size_t blocks = 0;      // summed-volume tables built
};

// For every occupied voxel c: N(c) = occupied voxels in the window_size^3 cube
// centred on c; c is a candidate when |N(c + s) - N(c)| >= tau_change for all
// 26 unit shifts s. Window sums come from summed-volume tables over the dense
// bounding box when it fits in max_table_bytes, otherwise over blocks.
// REQUIRES: window_size odd >= 3, tau_change >= 1.
StatusOr<WindowCandidates> FindWindowCandidates(const VoxelGrid& grid, int window_size,
                                                int tau_change, std::size_t max_table_bytes);

}  // namespace mapd::voxel::internal

#endif  // MAPD_VOXEL_CORNER_WINDOW_H_
