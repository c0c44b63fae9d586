// Exact nearest neighbour within a few voxels: ICP's correspondence search
// (icp.cc).
//
// The points are binned in cubic cells of one voxel. A query scans rings of
// cells outwards from its own and stops as soon as the best distance is
// below the next ring's bound (usually after the 27 cells around it). Two
// bit sets over the cells' box answer most of the work: `near` says whether
// any point lies within kReachCells of a cell (most queries of a wrong
// alignment, and those outside the overlap, stop there), `occupied` which
// cells hold a point. A row of up to 64 cells along x is one or two word
// reads of `occupied`, and a cell's points are found by the rank of its bit
// (a prefix count per word plus a popcount), not by hashing. Boxes of more
// than kMaxBits cells keep no bits and fall back to a hash of the cells.
//
// Ties (two points at exactly the same distance) go to the lower index, so
// the answer does not depend on the scan order.
//
// A query may be limited to the points inside a box: the answer is then
// the one an index of just those points would give (index for index, in
// the order given), so one index of a map serves every ICP run against it
// (icp.h, IcpTarget), each with its own overlap.
//
// Thread compatible: const methods may be called concurrently.
#ifndef MAPD_VOXEL_NEAREST_VOXEL_H_
#define MAPD_VOXEL_NEAREST_VOXEL_H_

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <unordered_map>
#include <utility>
#include <vector>

#include "voxel/cell_bits.h"
#include "voxel/memory_bytes.h"

namespace mapd::voxel {

class NearestVoxelIndex {
 public:
  // Cells whose `near` bit is kept (ICP asks within 3 voxels by default).
  static constexpr int kReachCells = 3;
  // Above this many cells in the points' box (32 MiB of bits), the hash.
  static constexpr std::size_t kMaxBits = std::size_t{1} << 28;

  // REQUIRES: cell_m > 0, points finite.
  NearestVoxelIndex(const std::vector<Eigen::Vector3d>& points, double cell_m);

  // Index of the nearest point within max_m of q (-1 if none) and its
  // squared distance (max_m^2 when none). Only points inside `within`
  // (AlignedBox3d::contains, bounds included) count when it is non-null.
  // With others_m2, when a point is found: a lower bound on the squared
  // distance from q of every other point that counts (those within max_m and
  // beyond: the nearest other point the scan met, or the distance beyond
  // which it did not look). ICP uses it to keep a pairing exactly while its
  // query moves less than the gap (icp.cc, StillNearest).
  int Nearest(const Eigen::Vector3d& q, double max_m, float* squared_m2,
              const Eigen::AlignedBox3d* within = nullptr, double* others_m2 = nullptr) const;

  // Whether the bit sets are kept (false: the hash answers).
  bool dense() const { return !occupied_.empty(); }

  // Heap bytes held, approximately (voxel/memory_bytes.h).
  std::size_t MemoryBytes() const {
    return near_.MemoryBytes() + occupied_.MemoryBytes() + voxel::MemoryBytes(rank_) +
           voxel::MemoryBytes(first_) + voxel::MemoryBytes(sorted_) + voxel::MemoryBytes(order_) +
           voxel::MemoryBytes(cells_);
  }

 private:
  // The best point so far: the nearest, ties to the lower index.
  struct Best {
    double squared_m2;
    const Eigen::AlignedBox3d* within;  // null: every point counts
    int index = -1;
    double others_m2 = HUGE_VAL;  // the nearest point offered but not kept
    void Offer(double d, int i) {
      if (d < squared_m2 || (d == squared_m2 && (index < 0 || i < index))) {
        if (index >= 0) others_m2 = std::min(others_m2, squared_m2);
        squared_m2 = d;
        index = i;
      } else {
        others_m2 = std::min(others_m2, d);
      }
    }
  };

  Eigen::Vector3i Cell(const Eigen::Vector3d& p) const;
  void MarkNear(const std::vector<Eigen::Vector3i>& cells);
  // Offers the points of the cells of one row along x: x in [x0, x1], at (y, z).
  void ScanRow(int x0, int x1, int y, int z, bool ends_only, const Eigen::Vector3d& q,
               Best* best) const;
  void ScanCellHashed(const Eigen::Vector3i& cell, const Eigen::Vector3d& q, Best* best) const;
  // Offers the points of the cell at bit i of occupied_.
  void OfferCell(std::size_t i, const Eigen::Vector3d& q, Best* best) const;
  // Offers sorted_[begin, end).
  void OfferPoints(int begin, int end, const Eigen::Vector3d& q, Best* best) const;

  double cell_m_;
  CellBits near_;      // over the points' cell box grown by kReachCells
  CellBits occupied_;  // over the points' cell box; empty: the hash
  // Dense: rank_[w] = set bits of occupied_ before word w; the points of the
  // k-th occupied cell (in bit order) are sorted_[first_[k] .. first_[k + 1]).
  std::vector<std::uint32_t> rank_;
  std::vector<int> first_;
  // The points in cell order (contiguous for the scan) and their indices.
  std::vector<Eigen::Vector3d> sorted_;
  std::vector<int> order_;
  // Hash fallback: packed cell -> (start in sorted_, count).
  std::unordered_map<std::uint64_t, std::pair<int, int>> cells_;
};

}  // namespace mapd::voxel

#endif  // MAPD_VOXEL_NEAREST_VOXEL_H_
