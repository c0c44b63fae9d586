// One bit per cell of a box of integer cells (voxel keys or hash cells): a
// membership test that costs one memory read, for sets too dense to hash
// cheaply. Used by ICP's neighbour index (icp.cc) and the overlap score's
// index of A (merge_overlap.h).
//
// Thread compatible: const methods may be called concurrently.
#ifndef MAPD_VOXEL_CELL_BITS_H_
#define MAPD_VOXEL_CELL_BITS_H_

#include <Eigen/Core>
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace mapd::voxel {

struct CellBits {
  Eigen::Vector3i lo = Eigen::Vector3i::Zero();    // the box's first cell
  Eigen::Vector3i size = Eigen::Vector3i::Zero();  // and its extent, in cells
  std::vector<std::uint64_t> words;                // empty: no bits kept

  // A box of `extent` cells from `first`, all clear; false (and no bits) when
  // it has more than max_cells cells.
  bool Reset(const Eigen::Vector3i& first, const Eigen::Vector3i& extent, std::size_t max_cells) {
    const double count = static_cast<double>(extent.x()) * extent.y() * extent.z();
    if (count > static_cast<double>(max_cells)) return false;
    lo = first;
    size = extent;
    words.assign(static_cast<std::size_t>(count) / 64 + 1, 0);
    return true;
  }
  bool empty() const { return words.empty(); }
  std::size_t MemoryBytes() const { return words.capacity() * sizeof(std::uint64_t); }
  bool Contains(const Eigen::Vector3i& c) const {
    const Eigen::Vector3i o = c - lo;
    return !empty() && (o.array() >= 0).all() && (o.array() < size.array()).all();
  }
  // REQUIRES: Contains(c).
  void Set(const Eigen::Vector3i& c) {
    const std::size_t i = Index(c - lo);
    words[i >> 6] |= std::uint64_t{1} << (i & 63);
  }
  // Sets the row of cells from `first` to x = last_x (same y and z).
  // REQUIRES: Contains(first), first.x() <= last_x < lo.x() + size.x().
  void SetRow(const Eigen::Vector3i& first, int last_x) {
    std::size_t i = Index(first - lo);
    const std::size_t end = i + static_cast<std::size_t>(last_x - first.x()) + 1;
    while (i < end) {
      const std::size_t bit = i & 63;
      const std::size_t count = std::min<std::size_t>(64 - bit, end - i);
      const std::uint64_t ones = count == 64 ? ~std::uint64_t{0} : (std::uint64_t{1} << count) - 1;
      words[i >> 6] |= ones << bit;
      i += count;
    }
  }
  // Cells outside the box (or with no bits kept) read as clear.
  bool Test(const Eigen::Vector3i& c) const {
    if (!Contains(c)) return false;
    const std::size_t i = Index(c - lo);
    return (words[i >> 6] >> (i & 63)) & 1;
  }
  // o: a cell's offset from lo, inside the box; x varies fastest.
  std::size_t Index(const Eigen::Vector3i& o) const {
    return (static_cast<std::size_t>(o.z()) * static_cast<std::size_t>(size.y()) +
            static_cast<std::size_t>(o.y())) *
               static_cast<std::size_t>(size.x()) +
           static_cast<std::size_t>(o.x());
  }
};

}  // namespace mapd::voxel

#endif  // MAPD_VOXEL_CELL_BITS_H_
