#include "voxel/corner_voxel_index.h"

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

}  // namespace mapd::voxel::internal
