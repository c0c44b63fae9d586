#include "voxel/voxel_grid.h"

#include <octomap/OcTree.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <string>

#include "voxel/octree_leaves.h"

namespace mapd::voxel {
namespace {

constexpr int kKeyOffset = 32768;  // OctoMap's key of the origin voxel

bool InRange(const VoxelKey& key) {
  return (key.array() >= -kKeyOffset).all() && (key.array() < kKeyOffset).all();
}

// REQUIRES: InRange(key).
std::uint64_t Pack(const VoxelKey& key, int level) {
  const auto x = static_cast<std::uint64_t>(key.x() + kKeyOffset) >> level;
  const auto y = static_cast<std::uint64_t>(key.y() + kKeyOffset) >> level;
  const auto z = static_cast<std::uint64_t>(key.z() + kKeyOffset) >> level;
  return x | (y << 16) | (z << 32);
}

// The inverse of Pack: the cube's minimum key.
VoxelKey Unpack(std::uint64_t packed, int level) {
  const auto axis = [&](int shift) {
    return (static_cast<int>((packed >> shift) & 0xffff) << level) - kKeyOffset;
  };
  return VoxelKey(axis(0), axis(16), axis(32));
}

bool KeyLess(const VoxelKey& a, const VoxelKey& b) {
  return std::lexicographical_compare(a.data(), a.data() + 3, b.data(), b.data() + 3);
}

}  // namespace

void VoxelGrid::AddFreeCube(const VoxelKey& min_key, int level) {
  free_[static_cast<std::size_t>(level)].insert(Pack(min_key, level));
}

void VoxelGrid::Finish() {
  std::sort(occupied_keys_.begin(), occupied_keys_.end(), KeyLess);
  occupied_keys_.erase(std::unique(occupied_keys_.begin(), occupied_keys_.end()),
                       occupied_keys_.end());
  occupied_.clear();
  occupied_.reserve(occupied_keys_.size());
  occupied_centres_.clear();
  occupied_centres_.reserve(occupied_keys_.size());
  min_key_ = VoxelKey::Zero();
  max_key_ = VoxelKey::Zero();
  if (!occupied_keys_.empty()) {
    min_key_ = max_key_ = occupied_keys_.front();
  }
  for (const VoxelKey& key : occupied_keys_) {
    occupied_.insert(Pack(key, 0));
    occupied_centres_.push_back(KeyToCentre(key));
    min_key_ = min_key_.cwiseMin(key);
    max_key_ = max_key_.cwiseMax(key);
  }
}

StatusOr<VoxelGrid> VoxelGrid::FromOcTree(const octomap::OcTree& tree,
                                          const VoxelGridLimits& limits) {
  VoxelGrid grid;
  grid.resolution_ = tree.getResolution();
  const int max_depth = static_cast<int>(tree.getTreeDepth());
  // First pass: count the occupied voxels before expanding anything.
  std::uint64_t occupied = 0;
  std::array<std::size_t, kLevels> free_cubes{};  // per level, to size the sets once
  // (The leaves' volumes sum to at most the key space's 2^48 voxels: no overflow.)
  ForEachLeaf(tree, [&](const octomap::OcTreeNode& node, const octomap::OcTreeKey&, unsigned d) {
    const int level = max_depth - static_cast<int>(d);
    if (!tree.isNodeOccupied(node)) {
      if (level < kLevels) ++free_cubes[static_cast<std::size_t>(level)];
      return;
    }
    occupied += std::uint64_t{1} << (3 * level);
  });
  if (occupied > limits.max_occupied_voxels) {
    return Status::ResourceExhausted("octree has more than " +
                                     std::to_string(limits.max_occupied_voxels) +
                                     " occupied voxels at the finest resolution");
  }
  grid.occupied_keys_.reserve(occupied);
  for (std::size_t level = 0; level < free_cubes.size(); ++level) {
    grid.free_[level].reserve(free_cubes[level]);
  }
  ForEachLeaf(tree, [&](const octomap::OcTreeNode& node, const octomap::OcTreeKey& k, unsigned d) {
    const int level = max_depth - static_cast<int>(d);
    // A leaf of depth d covers the aligned cube of edge 2^level that holds its key.
    const VoxelKey min_key((static_cast<int>(k[0]) >> level << level) - kKeyOffset,
                           (static_cast<int>(k[1]) >> level << level) - kKeyOffset,
                           (static_cast<int>(k[2]) >> level << level) - kKeyOffset);
    if (!tree.isNodeOccupied(node)) {
      grid.AddFreeCube(min_key, level);
      return;
    }
    const int edge = 1 << level;
    for (int dx = 0; dx < edge; ++dx) {
      for (int dy = 0; dy < edge; ++dy) {
        for (int dz = 0; dz < edge; ++dz) {
          grid.occupied_keys_.push_back(min_key + VoxelKey(dx, dy, dz));
        }
      }
    }
  });
  grid.Finish();
  return grid;
}

StatusOr<VoxelGrid> VoxelGrid::FromKeys(double resolution, const std::vector<VoxelKey>& occupied,
                                        const std::vector<VoxelKey>& free) {
  if (!std::isfinite(resolution) || resolution <= 0.0) {
    return Status::InvalidArgument("resolution must be finite and > 0");
  }
  for (const auto* keys : {&occupied, &free}) {
    for (const VoxelKey& key : *keys) {
      if (!InRange(key)) {
        return Status::InvalidArgument("voxel key outside [-32768, 32767]");
      }
    }
  }
  VoxelGrid grid;
  grid.resolution_ = resolution;
  grid.occupied_keys_ = occupied;
  for (const VoxelKey& key : free) grid.AddFreeCube(key, 0);
  grid.Finish();
  return grid;
}

bool VoxelGrid::IsOccupied(const VoxelKey& key) const {
  return InRange(key) && occupied_.contains(Pack(key, 0));
}

VoxelState VoxelGrid::State(const VoxelKey& key) const {
  if (!InRange(key)) return VoxelState::kUnknown;
  if (occupied_.contains(Pack(key, 0))) return VoxelState::kOccupied;
  for (int level = 0; level < kLevels; ++level) {
    const auto& cubes = free_[static_cast<std::size_t>(level)];
    if (!cubes.empty() && cubes.contains(Pack(key, level))) return VoxelState::kFree;
  }
  return VoxelState::kUnknown;
}

void VoxelGrid::ForEachFreeCube(
    const std::function<void(const VoxelKey& min_key, int edge)>& fn) const {
  for (int level = 0; level < kLevels; ++level) {
    for (std::uint64_t packed : free_[static_cast<std::size_t>(level)].keys())
      fn(Unpack(packed, level), 1 << level);
  }
}

VoxelKey VoxelGrid::PointToKey(const Eigen::Vector3d& point) const {
  // Clamped so that far or non-finite points give an out-of-range key, not UB.
  const Eigen::Vector3d scaled =
      (point / resolution_).cwiseMax(-1e9).cwiseMin(1e9).unaryExpr([](double v) {
        return std::isnan(v) ? 1e9 : v;
      });
  return VoxelKey(static_cast<int>(std::floor(scaled.x())),
                  static_cast<int>(std::floor(scaled.y())),
                  static_cast<int>(std::floor(scaled.z())));
}

std::size_t VoxelGrid::MemoryBytes() const {
  std::size_t bytes = occupied_keys_.capacity() * sizeof(VoxelKey) +
                      occupied_centres_.capacity() * sizeof(Eigen::Vector3d) +
                      occupied_.MemoryBytes();
  for (const PackedKeySet& cubes : free_) bytes += cubes.MemoryBytes();
  return bytes;
}

}  // namespace mapd::voxel
