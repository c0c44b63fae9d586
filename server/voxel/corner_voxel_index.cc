#include "voxel/corner_voxel_index.h"

#include <algorithm>

namespace mapd::voxel::internal {

VoxelIndex::VoxelIndex(const std::vector<VoxelKey>& keys) {
  constexpr int kCells = kBrick * kBrick * kBrick;
  for (std::size_t i = 0; i < keys.size(); ++i) {
    const VoxelKey& k = keys[i];
    const auto [it, inserted] = bricks_.emplace(
        Pack(k.x() >> kBrickBits, k.y() >> kBrickBits, k.z() >> kBrickBits), cells_.size());
    if (inserted) cells_.resize(cells_.size() + kCells, -1);
    const int mask = kBrick - 1;
    const std::size_t cell = static_cast<std::size_t>(
        (((k.x() & mask) << kBrickBits) + (k.y() & mask)) * kBrick + (k.z() & mask));
    cells_[it->second + cell] = static_cast<std::int32_t>(i);
  }
}

int VoxelIndex::Find(const VoxelKey& key) const {
  const std::int32_t* brick =
      Brick(key.x() >> kBrickBits, key.y() >> kBrickBits, key.z() >> kBrickBits);
  if (brick == nullptr) return -1;
  const int mask = kBrick - 1;
  return brick[(((key.x() & mask) << kBrickBits) + (key.y() & mask)) * kBrick + (key.z() & mask)];
}

void VoxelIndex::FillOccupancy(const VoxelKey& lo, int edge, std::uint8_t* out) const {
  std::fill_n(out, static_cast<std::size_t>(edge) * edge * edge, std::uint8_t{0});
  ForEachRow(lo, lo + VoxelKey::Constant(edge - 1),
             [&](const std::int32_t* cells, const VoxelKey& first, int count) {
               const VoxelKey at = first - lo;
               std::uint8_t* to =
                   out + (static_cast<std::size_t>(at.x()) * edge + at.y()) * edge + at.z();
               for (int z = 0; z < count; ++z) to[z] = cells[z] >= 0 ? 1 : 0;
             });
}

}  // namespace mapd::voxel::internal
