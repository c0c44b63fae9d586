// The global map (issue 42 item 4; docs/operations.md, "The global map"): the
// union, in the map frame, of every submap whose place there is known, fused
// one after another by the merge's occupancy rule (occupancy_fusion.h).
//
// Built incrementally: a new member is fused into the map as it stands, so an
// accepted merge costs the fusion of the submaps it placed, not of the whole
// map. Removing a member needs a rebuild (fusion cannot be undone): the
// caller passes an empty base and every remaining member, in the order they
// first joined, so that the rebuilt map is the one an incremental build of
// that history would have made.
//
// Pure function of its inputs; thread compatible.
#ifndef MAPD_VOXEL_GLOBAL_MAP_H_
#define MAPD_VOXEL_GLOBAL_MAP_H_

#include <Eigen/Geometry>
#include <atomic>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "common/status.h"
#include "voxel/occupancy_fusion.h"

namespace mapd::voxel {

// A submap and where it sits in the map frame.
struct PlacedSubmap {
  uint64_t id = 0;
  Eigen::Isometry3d T_map_submap = Eigen::Isometry3d::Identity();
  std::string_view bytes;  // .bt or .ot; parsed by ReadOctree (untrusted)
};

struct GlobalMapBuild {
  std::string bt;           // the map as an OctoMap .bt file
  double resolution_m = 0;  // the map's voxel size, metres
  uint64_t occupied_voxels = 0;
  uint64_t free_voxels = 0;
  uint64_t free_voxels_skipped = 0;  // left out by FusionParams::max_free_voxels
};

// Fuses `members` in order into `base_bt` (the map so far; empty: a new map
// at the finest resolution of the members). A member of another resolution
// is resampled into the map's grid (a finer one loses detail: the caller
// rebuilds when a finer member joins). InvalidArgument for unreadable bytes
// (naming the submap), a non-finite pose, or an empty base without members.
//
// `stop` (may be null) is read before each member is read or fused and
// before the map is written: once it is set, the build ends with Unavailable
// and nothing (a server shutting down does not wait for a whole build; the
// fusion of the member in progress is finished first).
StatusOr<GlobalMapBuild> ExtendGlobalMap(std::string_view base_bt,
                                         const std::vector<PlacedSubmap>& members,
                                         const FusionParams& params,
                                         const std::atomic<bool>* stop = nullptr);

}  // namespace mapd::voxel

#endif  // MAPD_VOXEL_GLOBAL_MAP_H_
