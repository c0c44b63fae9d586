// The overlap score of a candidate alignment (docs/algorithms.md B.4 tie-break
// and B.5 acceptance, Eq. 31), on plain voxel grids.
//
// Definition: every occupied voxel b of B is mapped into A (centre through
// T_a_b, then A's voxel k containing it). b is OBSERVED when A knows k (free
// or occupied) or has an occupied voxel within one voxel of k; b COINCIDES
// when A has an occupied voxel at k or at one of its 26 neighbours (one voxel
// of tolerance: a wall rasterised in two rotated grids does not hit the same
// voxels). score = coinciding / observed, in [0, 1]; 0 when nothing is
// observed. B's voxels that fall in A's unknown space do not count either
// way: a partial overlap is not penalised, a B wall in A's free space is.
//
// Thread compatible; no shared state.
#ifndef MAPD_VOXEL_MERGE_OVERLAP_H_
#define MAPD_VOXEL_MERGE_OVERLAP_H_

#include <Eigen/Geometry>
#include <cstddef>
#include <cstdint>

#include "voxel/voxel_grid.h"

namespace mapd::voxel {

struct OverlapScore {
  std::uint64_t observed = 0;    // B's occupied voxels that fall on A's observed space
  std::uint64_t coinciding = 0;  // of those, on (or next to) an occupied voxel of A
  double score = 0.0;            // coinciding / observed, 0 when observed == 0
};

// Evaluates at most `max_points` voxels of B (an even, deterministic
// subsample; 0 = all), so the tie-break over several candidate transforms
// stays cheap. The counts are of the evaluated voxels.
OverlapScore ComputeOverlapScore(const VoxelGrid& a, const VoxelGrid& b,
                                 const Eigen::Isometry3d& T_a_b, std::size_t max_points = 0);

}  // namespace mapd::voxel

#endif  // MAPD_VOXEL_MERGE_OVERLAP_H_
