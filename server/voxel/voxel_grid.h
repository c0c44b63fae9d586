// A read-only view of an occupancy octree at its finest resolution, as plain
// data (no OctoMap types): the occupied voxels expanded to unit keys, and the
// free leaves kept as cubes so that free and unknown space stay distinct for
// fusion (docs/algorithms.md B.6).
//
// Keys: integer voxel indices; voxel `key` spans
// [key * resolution, (key + 1) * resolution) per axis, centre (key + 0.5) * res.
// They equal OctoMap's keys minus 32768, so valid keys lie in [-32768, 32767].
// Thread safety: immutable after construction; const methods are safe to call
// concurrently.
#ifndef MAPD_VOXEL_VOXEL_GRID_H_
#define MAPD_VOXEL_VOXEL_GRID_H_

#include <Eigen/Core>
#include <array>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <vector>

#include "common/status.h"
#include "voxel/packed_key_set.h"

namespace octomap {
class OcTree;
}  // namespace octomap

namespace mapd::voxel {

using VoxelKey = Eigen::Vector3i;

enum class VoxelState { kUnknown, kFree, kOccupied };

struct VoxelGridLimits {
  // Occupied voxels after expansion to the finest resolution. A valid octree
  // can hold an occupied leaf of 2^45 voxels; such a map is refused, not built.
  std::size_t max_occupied_voxels = 20'000'000;
};

class VoxelGrid {
 public:
  // An empty grid (every voxel unknown) with resolution 1 m.
  VoxelGrid() = default;

  // The occupied leaves (OcTree::isNodeOccupied) expanded to finest keys; the
  // free leaves as cubes. ResourceExhausted beyond `limits`.
  static StatusOr<VoxelGrid> FromOcTree(const octomap::OcTree& tree,
                                        const VoxelGridLimits& limits = {});

  // From plain keys (generated maps, tests). Duplicates are merged; a key both
  // occupied and free counts as occupied. InvalidArgument for a resolution that
  // is not finite and > 0 or a key outside [-32768, 32767].
  static StatusOr<VoxelGrid> FromKeys(double resolution, const std::vector<VoxelKey>& occupied,
                                      const std::vector<VoxelKey>& free = {});

  double resolution() const { return resolution_; }  // metres
  std::size_t num_occupied() const { return occupied_keys_.size(); }
  bool empty() const { return occupied_keys_.empty(); }

  // Occupied voxels in lexicographic (x, y, z) key order; centres in metres in
  // the same order.
  const std::vector<VoxelKey>& occupied_keys() const { return occupied_keys_; }
  const std::vector<Eigen::Vector3d>& occupied_centres() const { return occupied_centres_; }

  // Inclusive key bounds of the occupied voxels. REQUIRES: !empty().
  const VoxelKey& min_key() const { return min_key_; }
  const VoxelKey& max_key() const { return max_key_; }
  // Metric bounds (voxel faces, not centres) of the occupied voxels.
  Eigen::Vector3d min_corner() const { return min_key_.cast<double>() * resolution_; }
  Eigen::Vector3d max_corner() const {
    return (max_key_.cast<double>() + Eigen::Vector3d::Ones()) * resolution_;
  }

  bool IsOccupied(const VoxelKey& key) const;
  // kOccupied, kFree (inside a free leaf) or kUnknown (never observed, or a key
  // outside the octree's range).
  VoxelState State(const VoxelKey& key) const;

  Eigen::Vector3d KeyToCentre(const VoxelKey& key) const {
    return (key.cast<double>() + Eigen::Vector3d::Constant(0.5)) * resolution_;
  }
  // The voxel containing `point` (metres).
  VoxelKey PointToKey(const Eigen::Vector3d& point) const;

  // Calls fn(min_key, edge) for every free cube: the voxels min_key + [0, edge)
  // per axis (edge = 2^level voxels), smallest cubes first, each size in the
  // order the map gave them (FromOcTree: its leaves'). For views that need
  // free space per region (mapctl occupancy-grid) without probing key by key.
  void ForEachFreeCube(const std::function<void(const VoxelKey& min_key, int edge)>& fn) const;
  // Heap bytes held.
  std::size_t MemoryBytes() const;
  // At least one free voxel (maps built from points alone carry none).
  bool has_free_space() const {
    for (const auto& cubes : free_) {
      if (!cubes.empty()) return true;
    }
    return false;
  }

 private:
  static constexpr int kLevels = 17;  // cube edge 2^level voxels, level 0 = finest

  void AddFreeCube(const VoxelKey& min_key, int level);
  void Finish();

  double resolution_ = 1.0;
  std::vector<VoxelKey> occupied_keys_;
  std::vector<Eigen::Vector3d> occupied_centres_;
  PackedKeySet occupied_;  // packed keys
  // free_[level] holds packed (key >> level) of free cubes of that level.
  std::array<PackedKeySet, kLevels> free_;
  VoxelKey min_key_ = VoxelKey::Zero();
  VoxelKey max_key_ = VoxelKey::Zero();
};

}  // namespace mapd::voxel

#endif  // MAPD_VOXEL_VOXEL_GRID_H_
