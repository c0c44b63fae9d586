// A safe reader for OctoMap occupancy octrees (.bt binary and .ot full files).
//
// OctoMap's own readers trust their input: Debian's OctoMap 1.9.7 recurses once
// per tree level with no depth limit (a 200 KB chain overflows the stack),
// accepts trees deeper than its 16 levels, and allocates every node before it
// compares the node count with the header. So untrusted bytes go through our
// own iterative parser first (ValidateOctree); only bytes that pass are handed
// to OctoMap's reader, behind a canonical header that we write ourselves.
//
// Thread safety: the functions are reentrant; they share no state.
#ifndef MAPD_VOXEL_OCTREE_READER_H_
#define MAPD_VOXEL_OCTREE_READER_H_

#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <string_view>

#include "common/status.h"

namespace octomap {
class OcTree;
}  // namespace octomap

namespace mapd::voxel {

// Limits applied before anything is allocated.
struct OctreeReadLimits {
  // Upper bound on the input size in bytes AND on the estimated memory of the
  // decoded tree (kOctreeBytesPerNode per node), so the node cap is
  // max_bytes / kOctreeBytesPerNode. The default admits ~5.6 M nodes; the
  // largest shared map (new_college.bt) has 2.6 M.
  std::size_t max_bytes = std::size_t{256} << 20;
  // Occupied voxels at the finest resolution after expansion (an occupied
  // leaf at depth d stands for 8^(16-d) of them): counted during the walk,
  // before OctoMap or VoxelGrid allocate anything, so that a small file that
  // expands to a huge grid is refused (a 599 KB .bt can expand to 16.8 M
  // voxels). 0 = no limit (the default: building a VoxelGrid has its own
  // limit; mapd sets limits.max_submap_voxels here for uploads).
  std::uint64_t max_occupied_voxels = 0;
};

// Estimated heap bytes per OctoMap node (16-byte node plus malloc overhead plus
// a share of the 64-byte child-pointer arrays of inner nodes).
inline constexpr std::size_t kOctreeBytesPerNode = 48;
// OctoMap's fixed tree depth: leaves at depth 16, the finest resolution.
inline constexpr int kOctreeMaxDepth = 16;

enum class OctreeFormat {
  kBinary,  // .bt "# Octomap OcTree binary file": 2 bits per child, max-likelihood
  kFull,    // .ot "# Octomap OcTree file": float log-odds + child mask per node
};

// What the validator learned about well-formed input.
struct OctreeSummary {
  OctreeFormat format = OctreeFormat::kBinary;
  double resolution = 0.0;      // metres, finite and > 0
  std::uint64_t num_nodes = 0;  // equals the header's `size`
  int max_depth = 0;            // deepest node, root = 0, <= kOctreeMaxDepth
  std::size_t data_offset = 0;  // first byte after the `data` line
  // Leaves expanded to the finest resolution, as VoxelGrid::FromOcTree and
  // OcTree::isNodeOccupied see them (.ot: log-odds >= 0 is occupied).
  std::uint64_t occupied_voxels = 0;
  std::uint64_t free_voxels = 0;  // saturates at 2^64 - 1
  // Inclusive key bounds of the occupied voxels (OctoMap keys minus 32768, as
  // VoxelGrid's); meaningful only when occupied_voxels > 0.
  std::int32_t occupied_min_key[3] = {0, 0, 0};
  std::int32_t occupied_max_key[3] = {0, 0, 0};
};

// Parses and checks `bytes` without building a tree: header grammar (magic
// line, `id OcTree`, `size`, `res`, `data`), resolution finite and in
// (0, 1000] m, depth <= 16, node count within the limit and equal to `size`,
// every byte consumed exactly, occupied voxels within the limit. Iterative: stack use does not
// depend on input. Errors: InvalidArgument for malformed input, ResourceExhausted for input beyond
// `limits`.
StatusOr<OctreeSummary> ValidateOctree(std::string_view bytes, const OctreeReadLimits& limits = {});

// Deletes an octomap::OcTree; lets callers hold one without OctoMap headers.
struct OcTreeDeleter {
  void operator()(octomap::OcTree* tree) const;
};
using OcTreePtr = std::unique_ptr<octomap::OcTree, OcTreeDeleter>;

// ValidateOctree, then OctoMap's own reader (readBinary for .bt,
// AbstractOcTree::read for .ot) on the validated bytes; checks that OctoMap
// consumed exactly those bytes and built exactly `size` nodes.
// The result is never null.
StatusOr<OcTreePtr> ReadOctree(std::string_view bytes, const OctreeReadLimits& limits = {});

// Reads the file (refusing one larger than limits.max_bytes before reading it)
// and calls ReadOctree. NotFound when the file cannot be opened.
StatusOr<OcTreePtr> ReadOctreeFile(const std::string& path, const OctreeReadLimits& limits = {});

// The tree as a .bt file (OctoMap writeBinaryConst: max-likelihood, pruned).
StatusOr<std::string> WriteBinaryOctree(const octomap::OcTree& tree);

// What the service stores about an uploaded submap (after validation).
struct SubmapSummary {
  double resolution = 0.0;  // metres
  uint64_t occupied_voxels = 0;
  uint64_t free_voxels = 0;
  Eigen::Vector3d bounds_min = Eigen::Vector3d::Zero();  // of the occupied voxels, metres
  Eigen::Vector3d bounds_max = Eigen::Vector3d::Zero();
};
// Validates the bytes (ValidateOctree: no tree is built, memory does not grow
// with the voxels) and summarises them; InvalidArgument names the problem,
// ResourceExhausted a file beyond `limits` (its expanded occupied voxels too).
StatusOr<SubmapSummary> InspectSubmap(std::string_view bytes, const OctreeReadLimits& limits = {});

}  // namespace mapd::voxel

#endif  // MAPD_VOXEL_OCTREE_READER_H_
