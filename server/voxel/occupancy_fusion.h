// Occupancy fusion of aligned submaps (docs/algorithms.md B.6; grid-map-fusion
// paper, Qiu et al., section IV.D) on OctoMap trees.
//
// kOverlapRule, the paper's words: "in the overlapping area of map A and map
// B, if the cube is occupied in map A or map B, the cube is still occupied
// after fusion. If the cube is free in both map A and map B, the cube is free
// after fusion, otherwise the merged cube is unknown." Outside the overlap
// each map keeps its own cells (docs/algorithms.md B.6).
// The OVERLAP is a region, not a per-voxel test (with "observed in both" the
// "otherwise unknown" clause could never apply): the voxels whose centre lies
// inside A's observed bounds (the axis-aligned box of all of A's leaves, free
// and occupied, in A's frame) AND inside B's observed bounds (the same box of
// B, in B's frame, so an oriented box in A's frame). Hence, per voxel:
//   occupied in A or B                      -> occupied (anywhere)
//   free in both                            -> free
//   free in one, unknown in the other:
//       inside the overlap                  -> unknown
//       outside (only one map covers it)    -> free
// kLogOdds: the log-odds of both maps are added (unknown = 0) and clamped to
// the merged tree's clamping thresholds (OctoMap's updateNode).
//
// B is resampled into the merged grid by inverse mapping: a merged voxel takes
// B's state when its centre, mapped back into B, lies inside B's leaf (no holes
// or double hits under rotation, and it handles different resolutions).
//
// Free space can be huge (one free leaf may stand for 2^30 voxels), so the
// voxel-level work on free space is capped (max_free_voxels): free leaves are
// processed smallest first, and a free leaf that would exceed the cap is left
// out, counted in FusionStats. Under kOverlapRule that leaves B's extra free
// space unknown (the safe side for navigation), and leaves A's free voxels of
// that leaf free instead of unknown; the counts say how much.
//
// Thread compatible: distinct trees may be fused concurrently.
#ifndef MAPD_VOXEL_OCCUPANCY_FUSION_H_
#define MAPD_VOXEL_OCCUPANCY_FUSION_H_

#include <Eigen/Geometry>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "common/status.h"
#include "voxel/octree_reader.h"

namespace octomap {
class OcTreeKey;
}  // namespace octomap

namespace mapd::voxel {

enum class FusionRule {
  kOverlapRule,  // the paper: occupied if occupied in either, free if free in both, else unknown
  kLogOdds,      // sum of log-odds (clamped), for maps that carry probabilities
};

enum class ResolutionPolicy {
  kRefuse,            // different resolutions: FailedPrecondition naming both
  kResampleToFinest,  // resample the coarser maps to the finest resolution
};

struct FusionParams {
  FusionRule rule = FusionRule::kOverlapRule;
  // Voxel-level operations on free space per fused submap (see above).
  std::uint64_t max_free_voxels = 8'000'000;
  // Threads for the voxel-level reading of the two maps (the writes into the
  // merged tree stay on the caller's): 1 to 256. The result does not depend
  // on it.
  int threads = 1;

  // InvalidArgument naming the first bad field.
  Status Validate() const;
};

struct FusionStats {
  std::uint64_t occupied_written = 0;     // B's occupied voxels written into the merged grid
  std::uint64_t free_written = 0;         // B's free voxels written (new free space)
  std::uint64_t free_cleared = 0;         // A's free voxels made unknown (overlap rule)
  std::uint64_t free_voxels_skipped = 0;  // free voxels left out by the cap
};

// A new tree at `resolution_m` holding `reference`: a copy when the
// resolutions are equal, otherwise `reference` resampled into the new grid
// (free space under the same cap). InvalidArgument for a bad resolution.
StatusOr<OcTreePtr> StartMergedMap(const octomap::OcTree& reference, double resolution_m,
                                   const FusionParams& params, FusionStats* stats = nullptr);

// Fuses `submap` into `merged` (REQUIRES: non-null), with T_merged_submap
// mapping the submap's frame into the merged map's frame, under params.rule.
Status FuseInto(const octomap::OcTree& submap, const Eigen::Isometry3d& T_merged_submap,
                const FusionParams& params, octomap::OcTree* merged, FusionStats* stats = nullptr);

// Occupied voxels of the tree at its finest resolution.
std::uint64_t CountOccupiedVoxels(const octomap::OcTree& tree);

namespace internal {
// The Morton code of a key: bit l of x, y and z at bits 3l, 3l + 1 and
// 3l + 2, so that (code >> 3l) & 7 is the child index at level l (OctoMap's
// computeChildIdx) and the voxels of a node of level l (8^l of them) are
// the consecutive codes from a multiple of 8^l.
std::uint64_t MortonCode(const octomap::OcTreeKey& key);

// Sets the voxels of `codes` (Morton codes, any order; sorted and made
// unique here) that `tree` does not know (tree->search finds nothing) to
// log_odds; returns how many it set. The same voxels and values as
// setNodeValue(key, log_odds, true) on each unknown one, and after a full
// prune the same tree, but each run of codes that fills a node is written as
// that node: a submap's free space is mostly large cubes, and a voxel at a
// time cost a walk from the root and a new node each (over a million for a
// campus crop pair). Inner nodes' values are left to updateInnerOccupancy.
std::uint64_t WriteUnknownVoxels(std::vector<std::uint64_t>* codes, float log_odds,
                                 octomap::OcTree* tree);
}  // namespace internal

}  // namespace mapd::voxel

#endif  // MAPD_VOXEL_OCCUPANCY_FUSION_H_
