#include "voxel/support/lattice_copy.h"

#include <octomap/OcTree.h>

#include <cstdio>
#include <cstdlib>
#include <sstream>

#include "voxel/octree_leaves.h"
#include "voxel/octree_reader.h"

namespace mapd::testing {
namespace {

voxel::OcTreePtr ReadOrDie(const std::string& bt) {
  auto tree = voxel::ReadOctree(bt);
  if (!tree.ok()) {
    std::fprintf(stderr, "lattice_copy: %s\n", tree.status().ToString().c_str());
    std::abort();
  }
  return std::move(*tree);
}

// Calls visit(key, occupied) for every voxel of every leaf.
template <typename Visit>
void ForEachVoxel(const octomap::OcTree& tree, std::uint64_t max_voxels, Visit&& visit) {
  std::uint64_t visited = 0;
  voxel::ForEachLeaf(
      tree, [&](const octomap::OcTreeNode& leaf, const octomap::OcTreeKey& key, unsigned depth) {
        // A leaf of depth d covers 2^(tree depth - d) keys per axis, from its
        // centre key minus half of them.
        const int size = 1 << (tree.getTreeDepth() - depth);
        const int half = size / 2;
        const bool occupied = tree.isNodeOccupied(leaf);
        visited += static_cast<std::uint64_t>(size) * size * size;
        if (visited > max_voxels) {
          std::fprintf(stderr, "lattice_copy: more than %llu voxels\n",
                       static_cast<unsigned long long>(max_voxels));
          std::abort();
        }
        for (int x = 0; x < size; ++x)
          for (int y = 0; y < size; ++y)
            for (int z = 0; z < size; ++z) {
              visit(octomap::OcTreeKey(key[0] - half + x, key[1] - half + y, key[2] - half + z),
                    occupied);
            }
      });
}

std::uint64_t Pack(const octomap::OcTreeKey& key) {
  return static_cast<std::uint64_t>(key[0]) << 32 | static_cast<std::uint64_t>(key[1]) << 16 |
         key[2];
}

}  // namespace

Eigen::Isometry3d LatticeMove::Transform(double resolution_m) const {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = rotation.cast<double>();
  T.translation() = shift_voxels.cast<double>() * resolution_m;
  return T;
}

std::string MoveByLattice(const std::string& bt, const LatticeMove& move,
                          std::uint64_t max_voxels) {
  const voxel::OcTreePtr in = ReadOrDie(bt);
  octomap::OcTree out(in->getResolution());
  ForEachVoxel(*in, max_voxels, [&](const octomap::OcTreeKey& key, bool occupied) {
    // Voxel centres sit at (key - 32768 + 1/2) r: in half voxels, u = 2 (key
    // - 32768) + 1, an odd number that a signed permutation keeps odd.
    Eigen::Vector3i u;
    for (int axis = 0; axis < 3; ++axis) u[axis] = 2 * (static_cast<int>(key[axis]) - 32768) + 1;
    const Eigen::Vector3i moved = move.rotation * u + 2 * move.shift_voxels;
    octomap::OcTreeKey out_key;
    for (int axis = 0; axis < 3; ++axis) {
      out_key[axis] = static_cast<octomap::key_type>((moved[axis] - 1) / 2 + 32768);
    }
    out.setNodeValue(out_key,
                     occupied ? out.getClampingThresMaxLog() : out.getClampingThresMinLog(),
                     /*lazy_eval=*/true);
  });
  out.updateInnerOccupancy();
  std::ostringstream bytes;
  out.writeBinary(bytes);
  return bytes.str();
}

VoxelStates StatesOf(const std::string& bt, std::uint64_t max_voxels) {
  const voxel::OcTreePtr tree = ReadOrDie(bt);
  VoxelStates states;
  ForEachVoxel(*tree, max_voxels, [&](const octomap::OcTreeKey& key, bool occupied) {
    states.emplace(Pack(key), occupied);
  });
  return states;
}

std::string DescribeDifference(const VoxelStates& actual, const VoxelStates& expected) {
  long extra = 0, missing = 0, occupied_for_free = 0, free_for_occupied = 0;
  for (const auto& [key, occupied] : actual) {
    const auto it = expected.find(key);
    if (it == expected.end()) {
      ++extra;
    } else if (occupied != it->second) {
      ++(occupied ? occupied_for_free : free_for_occupied);
    }
  }
  for (const auto& entry : expected) missing += actual.count(entry.first) == 0 ? 1 : 0;
  if (extra + missing + occupied_for_free + free_for_occupied == 0) return "";
  return std::to_string(extra) + " voxels known that should be unknown, " +
         std::to_string(missing) + " unknown that should be known, " +
         std::to_string(occupied_for_free) + " occupied that should be free, " +
         std::to_string(free_for_occupied) + " free that should be occupied (of " +
         std::to_string(expected.size()) + ")";
}

}  // namespace mapd::testing
