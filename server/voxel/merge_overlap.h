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
#include <vector>

#include "voxel/cell_bits.h"
#include "voxel/voxel_grid.h"

namespace mapd::voxel {

struct OverlapScore {
  std::uint64_t evaluated = 0;   // B's occupied voxels mapped (every `step`-th)
  std::size_t step = 1;          // B's voxels per evaluated one
  std::uint64_t observed = 0;    // of those, on A's observed space
  std::uint64_t coinciding = 0;  // of those, on (or next to) an occupied voxel of A
  double score = 0.0;            // coinciding / observed, 0 when observed == 0
};

// A's side of the score, computed once for the many transforms a merge scores
// (each corner solution's ties, each refined hypothesis): one bit per voxel
// of A's occupied box, plus one voxel, for "occupied within one voxel" and
// one for "observed". Answers as the grid does (exact): a profile of refused
// merges had a tenth of their CPU in the grid's hash lookups, up to 27 per
// point of B.
class OverlapIndex {
 public:
  // Bits only when the box has at most max_cells cells (2^28: 32 MiB a
  // set); beyond it, and outside the boxes, queries ask the grid.
  explicit OverlapIndex(const VoxelGrid& a, std::size_t max_cells = std::size_t{1} << 28);

  const VoxelGrid& grid() const { return *grid_; }
  bool has_bits() const { return !near_.empty(); }
  // The bits cover every voxel A knows (free space included), not only the
  // occupied box.
  bool observes_everywhere() const { return observed_everywhere_; }
  // A has an occupied voxel at `key` or at one of its 26 neighbours.
  bool OccupiedNear(const VoxelKey& key) const;
  // A knows `key` (free or occupied).
  bool Observed(const VoxelKey& key) const;
  // Heap bytes held.
  std::size_t MemoryBytes() const { return near_.MemoryBytes() + observed_.MemoryBytes(); }

 private:
  const VoxelGrid* grid_;
  CellBits near_;      // occupied voxels grown by one; no bits: ask the grid
  CellBits observed_;  // occupied or free, over every known voxel's box or else near_'s
  bool observed_everywhere_ = false;  // observed_ covers every voxel A knows
};

// Evaluates at most `max_points` voxels of B (an even, deterministic
// subsample; 0 = all), so the tie-break over several candidate transforms
// stays cheap. The counts are of the evaluated voxels.
OverlapScore ComputeOverlapScore(const VoxelGrid& a, const VoxelGrid& b,
                                 const Eigen::Isometry3d& T_a_b, std::size_t max_points = 0);
// The same, with A's side from `a` (same counts).
OverlapScore ComputeOverlapScore(const OverlapIndex& a, const VoxelGrid& b,
                                 const Eigen::Isometry3d& T_a_b, std::size_t max_points = 0);

// Free space both maps saw (the touching-placement gate,
// MergeParams::min_shared_free_ratio). B's free voxels are mapped into A
// (centre through T_a_b) and count as SHARED when they land on A's free space
// more than one voxel from A's occupied voxels: free space just behind a
// wall both maps share is not evidence that they saw the same side of it.
// A right merge shares the space in front of its coinciding walls; a
// placement that only puts B's wall on A's, B's room on the far side of it,
// shares none. Estimated on the voxels of B's free cubes whose keys are
// multiples of one stride per axis, the stride chosen for at most
// `max_points` of them (0 = every free voxel, up to kMaxSharedFreePoints: a
// map's free leaf can hold 2^48 voxels).
inline constexpr std::size_t kMaxSharedFreePoints = std::size_t{1} << 24;
struct SharedFree {
  std::uint64_t evaluated = 0;  // lattice voxels of B's free space mapped into A
  std::uint64_t shared = 0;     // of those, on A's free space as above
  int stride = 1;               // voxels per axis between lattice points
  // shared * stride^3: B's free voxels in A's free space (an estimate).
  double shared_voxels() const { return static_cast<double>(shared) * stride * stride * stride; }
};
SharedFree ComputeSharedFree(const OverlapIndex& a, const VoxelGrid& b,
                             const Eigen::Isometry3d& T_a_b, std::size_t max_points);

}  // namespace mapd::voxel

#endif  // MAPD_VOXEL_MERGE_OVERLAP_H_
