// Internal to corner extraction: O(1) look-up from a voxel key to the index of
// that occupied voxel, and cheap enumeration of the occupied voxels in a cube.
// Memory follows the occupied voxels (8^3 bricks, only where occupied), not
// the bounding box, so sparse outdoor maps cost no more than dense rooms.
#ifndef MAPD_VOXEL_CORNER_VOXEL_INDEX_H_
#define MAPD_VOXEL_CORNER_VOXEL_INDEX_H_

#include <cstdint>
#include <unordered_map>
#include <vector>

#include "voxel/memory_bytes.h"
#include "voxel/voxel_grid.h"

namespace mapd::voxel::internal {

class VoxelIndex {
 public:
  static constexpr int kBrickBits = 3;  // bricks of 8^3 voxels
  static constexpr int kBrick = 1 << kBrickBits;

  // keys[i] gets index i. Duplicate keys: the last one wins.
  explicit VoxelIndex(const std::vector<VoxelKey>& keys);

  // The index of the occupied voxel `key`, -1 when it is not occupied.
  int Find(const VoxelKey& key) const;

  // Heap bytes held, approximately (voxel/memory_bytes.h).
  std::size_t MemoryBytes() const {
    return voxel::MemoryBytes(bricks_) + voxel::MemoryBytes(cells_);
  }

  // out[((x * edge) + y) * edge + z] = 1 where lo + (x, y, z) is occupied, else
  // 0, for x, y, z in [0, edge): a dense copy of a small window.
  void FillOccupancy(const VoxelKey& lo, int edge, std::uint8_t* out) const;

  // Calls visit(index, offset) for every occupied voxel in the cube of
  // half-width `h` (voxels) centred on `centre`; offset = key - centre.
  template <typename Visit>
  void ForEachInCube(const VoxelKey& centre, int h, Visit&& visit) const {
    ForEachRow(centre - VoxelKey::Constant(h), centre + VoxelKey::Constant(h),
               [&](const std::int32_t* cells, const VoxelKey& first, int count) {
                 for (int z = 0; z < count; ++z) {
                   if (cells[z] >= 0) visit(cells[z], VoxelKey(first + VoxelKey(0, 0, z) - centre));
                 }
               });
  }

 private:
  // Calls visit(cells, first, count) for every run along z of the bricks'
  // cells inside the box [lo, hi] (inclusive): cells[k] is the index at key
  // first + (0, 0, k) (-1 when empty), k < count. Missing bricks are skipped.
  template <typename Visit>
  void ForEachRow(const VoxelKey& lo, const VoxelKey& hi, Visit&& visit) const {
    for (int bx = lo.x() >> kBrickBits; bx <= (hi.x() >> kBrickBits); ++bx) {
      for (int by = lo.y() >> kBrickBits; by <= (hi.y() >> kBrickBits); ++by) {
        for (int bz = lo.z() >> kBrickBits; bz <= (hi.z() >> kBrickBits); ++bz) {
          const std::int32_t* brick = Brick(bx, by, bz);
          if (brick == nullptr) continue;
          const VoxelKey base(bx * kBrick, by * kBrick, bz * kBrick);
          const VoxelKey a = lo.cwiseMax(base) - base;
          const VoxelKey b = hi.cwiseMin(base + VoxelKey::Constant(kBrick - 1)) - base;
          for (int x = a.x(); x <= b.x(); ++x) {
            for (int y = a.y(); y <= b.y(); ++y) {
              visit(brick + ((x << kBrickBits) + y) * kBrick + a.z(),
                    VoxelKey(base + VoxelKey(x, y, a.z())), b.z() - a.z() + 1);
            }
          }
        }
      }
    }
  }

  static std::uint64_t Pack(int bx, int by, int bz) {
    return (static_cast<std::uint64_t>(static_cast<std::uint32_t>(bx) & 0x1fffff) << 42) |
           (static_cast<std::uint64_t>(static_cast<std::uint32_t>(by) & 0x1fffff) << 21) |
           (static_cast<std::uint64_t>(static_cast<std::uint32_t>(bz) & 0x1fffff));
  }
  const std::int32_t* Brick(int bx, int by, int bz) const {
    const auto it = bricks_.find(Pack(bx, by, bz));
    return it == bricks_.end() ? nullptr : cells_.data() + it->second;
  }

  std::unordered_map<std::uint64_t, std::size_t> bricks_;  // brick -> offset in cells_
  std::vector<std::int32_t> cells_;                        // kBrick^3 per brick, -1 = empty
};

}  // namespace mapd::voxel::internal

#endif  // MAPD_VOXEL_CORNER_VOXEL_INDEX_H_
