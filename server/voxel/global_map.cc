#include "voxel/global_map.h"

#include <octomap/OcTree.h>

#include <algorithm>
#include <utility>

#include "voxel/octree_reader.h"

namespace mapd::voxel {
namespace {

StatusOr<OcTreePtr> ReadMember(const PlacedSubmap& member) {
  auto tree = ReadOctree(member.bytes);
  if (!tree.ok()) {
    return Status::InvalidArgument("submap " + std::to_string(member.id) +
                                   " cannot be read: " + tree.status().message());
  }
  return tree;
}

Status CheckNotStopped(const std::atomic<bool>* stop) {
  if (stop != nullptr && stop->load(std::memory_order_relaxed)) {
    return Status::Unavailable("the global map build was stopped");
  }
  return Status::Ok();
}

}  // namespace

StatusOr<GlobalMapBuild> ExtendGlobalMap(std::string_view base_bt,
                                         const std::vector<PlacedSubmap>& members,
                                         const FusionParams& params,
                                         const std::atomic<bool>* stop) {
  MAPD_RETURN_IF_ERROR(params.Validate());
  for (const PlacedSubmap& m : members) {
    if (!m.T_map_submap.matrix().allFinite()) {
      return Status::InvalidArgument("the pose of submap " + std::to_string(m.id) +
                                     " is not finite");
    }
  }
  FusionStats stats;
  OcTreePtr map;
  std::size_t next = 0;
  if (!base_bt.empty()) {
    auto base = ReadOctree(base_bt);
    if (!base.ok()) {
      return Status::InvalidArgument("the stored global map cannot be read: " +
                                     base.status().message());
    }
    map = std::move(base).value();
  } else {
    if (members.empty()) return Status::InvalidArgument("a global map needs a member");
    // The finest resolution among the members (each is read twice: the
    // trees are not all held at once).
    double finest = 0;
    for (const PlacedSubmap& m : members) {
      MAPD_RETURN_IF_ERROR(CheckNotStopped(stop));
      auto summary = InspectSubmap(m.bytes);
      if (!summary.ok()) {
        return Status::InvalidArgument("submap " + std::to_string(m.id) +
                                       " cannot be read: " + summary.status().message());
      }
      finest = finest == 0 ? summary->resolution : std::min(finest, summary->resolution);
    }
    auto first = ReadMember(members[0]);
    if (!first.ok()) return first.status();
    // A first member in the map frame at the map's resolution is the map so
    // far as it is (as a merge starts from its reference), else it is fused
    // into an empty map.
    if (members[0].T_map_submap.matrix() == Eigen::Matrix4d::Identity()) {
      auto started = StartMergedMap(**first, finest, params, &stats);
      if (!started.ok()) return started.status();
      map = std::move(started).value();
      next = 1;
    } else {
      map = OcTreePtr(new octomap::OcTree(finest));
    }
  }
  for (; next < members.size(); ++next) {
    MAPD_RETURN_IF_ERROR(CheckNotStopped(stop));
    auto tree = ReadMember(members[next]);
    if (!tree.ok()) return tree.status();
    MAPD_RETURN_IF_ERROR(FuseInto(**tree, members[next].T_map_submap, params, map.get(), &stats));
  }
  MAPD_RETURN_IF_ERROR(CheckNotStopped(stop));
  auto bytes = WriteBinaryOctree(*map);
  if (!bytes.ok()) return bytes.status();
  GlobalMapBuild build;
  build.bt = std::move(bytes).value();
  build.resolution_m = map->getResolution();
  auto summary = InspectSubmap(build.bt);
  if (!summary.ok()) return summary.status();
  build.occupied_voxels = summary->occupied_voxels;
  build.free_voxels = summary->free_voxels;
  build.free_voxels_skipped = stats.free_voxels_skipped;
  return build;
}

}  // namespace mapd::voxel
