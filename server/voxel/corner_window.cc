#include "voxel/corner_window.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <string>
#include <unordered_map>

namespace mapd::voxel::internal {
namespace {

using Index3 = Eigen::Matrix<std::int64_t, 3, 1>;

// Summed-volume table over a box of `extent` cells: table(i, j, k) is the
// number of occupied cells with local coordinates < (i, j, k).
class SummedVolume {
 public:
  SummedVolume(const Index3& extent, const VoxelKey& origin) : origin_(origin) {
    dims_ = extent + Index3::Ones();
    table_.assign(static_cast<std::size_t>(dims_.prod()), 0);
  }

  // REQUIRES: `key` inside the box.
  void Add(const VoxelKey& key) {
    const VoxelKey local = key - origin_;
    ++table_[At(local.x() + 1, local.y() + 1, local.z() + 1)];
  }

  void Integrate() {
    for (std::int64_t i = 1; i < dims_.x(); ++i)
      for (std::int64_t j = 0; j < dims_.y(); ++j)
        for (std::int64_t k = 0; k < dims_.z(); ++k) table_[At(i, j, k)] += table_[At(i - 1, j, k)];
    for (std::int64_t i = 0; i < dims_.x(); ++i)
      for (std::int64_t j = 1; j < dims_.y(); ++j)
        for (std::int64_t k = 0; k < dims_.z(); ++k) table_[At(i, j, k)] += table_[At(i, j - 1, k)];
    for (std::int64_t i = 0; i < dims_.x(); ++i)
      for (std::int64_t j = 0; j < dims_.y(); ++j)
        for (std::int64_t k = 1; k < dims_.z(); ++k) table_[At(i, j, k)] += table_[At(i, j, k - 1)];
  }

  // Occupied cells in the cube of half-width h centred on `key` (8 look-ups).
  // REQUIRES: the cube inside the box.
  int Window(const VoxelKey& key, int h) const {
    const VoxelKey lo = key - origin_ - VoxelKey::Constant(h);
    const VoxelKey hi = lo + VoxelKey::Constant(2 * h + 1);
    return table_[At(hi.x(), hi.y(), hi.z())] - table_[At(lo.x(), hi.y(), hi.z())] -
           table_[At(hi.x(), lo.y(), hi.z())] - table_[At(hi.x(), hi.y(), lo.z())] +
           table_[At(lo.x(), lo.y(), hi.z())] + table_[At(lo.x(), hi.y(), lo.z())] +
           table_[At(hi.x(), lo.y(), lo.z())] - table_[At(lo.x(), lo.y(), lo.z())];
  }

 private:
  std::size_t At(std::int64_t i, std::int64_t j, std::int64_t k) const {
    return static_cast<std::size_t>((i * dims_.y() + j) * dims_.z() + k);
  }

  VoxelKey origin_;
  Index3 dims_;
  std::vector<std::int32_t> table_;
};

bool IsCandidate(const SummedVolume& table, const VoxelKey& key, int h, int tau) {
  const int n0 = table.Window(key, h);
  for (int dx = -1; dx <= 1; ++dx) {
    for (int dy = -1; dy <= 1; ++dy) {
      for (int dz = -1; dz <= 1; ++dz) {
        if (dx == 0 && dy == 0 && dz == 0) continue;
        if (std::abs(table.Window(key + VoxelKey(dx, dy, dz), h) - n0) < tau) return false;
      }
    }
  }
  return true;
}

std::int64_t FloorDiv(std::int64_t a, std::int64_t b) {
  return a >= 0 ? a / b : -((-a + b - 1) / b);
}

struct Block {
  std::vector<VoxelKey> voxels;  // inside the block's extended region
  std::vector<VoxelKey> core;    // the block's own voxels, tested here
};

}  // namespace

StatusOr<WindowCandidates> FindWindowCandidates(const VoxelGrid& grid, int window_size,
                                                int tau_change, std::size_t max_table_bytes) {
  WindowCandidates result;
  if (grid.empty()) return result;
  const int h = window_size / 2;
  const int margin = h + 1;  // windows of the shifted centres reach this far
  const VoxelKey& min_key = grid.min_key();
  const Index3 dims = (grid.max_key() - min_key).cast<std::int64_t>() + Index3::Ones();
  const std::int64_t max_cells = static_cast<std::int64_t>(max_table_bytes / sizeof(std::int32_t));

  // Dense when the padded bounding box fits, otherwise cubic blocks whose
  // padded tables fit (at most 32 voxels a side: sparse maps waste less).
  Index3 block = dims;
  const Index3 dense_cells = dims + Index3::Constant(2 * margin + 1);
  const double dense = static_cast<double>(dense_cells.x()) * dense_cells.y() * dense_cells.z();
  if (dense > static_cast<double>(max_cells)) {
    const auto edge =
        static_cast<std::int64_t>(std::cbrt(static_cast<double>(max_cells))) - 2 * margin - 1;
    if (edge < 1) {
      return Status::ResourceExhausted("max_table_bytes " + std::to_string(max_table_bytes) +
                                       " cannot hold a summed-volume block for a " +
                                       std::to_string(window_size) + "^3 window");
    }
    block = Index3::Constant(std::min<std::int64_t>(edge, 32));
  }
  const Index3 num_blocks = (dims + block - Index3::Ones()).cwiseQuotient(block);

  std::unordered_map<std::int64_t, Block> blocks;
  auto block_id = [&](const Index3& b) {
    return (b.x() * num_blocks.y() + b.y()) * num_blocks.z() + b.z();
  };
  for (const VoxelKey& key : grid.occupied_keys()) {
    const Index3 r = (key - min_key).cast<std::int64_t>();
    Index3 lo, hi;
    for (int a = 0; a < 3; ++a) {
      lo[a] = std::max<std::int64_t>(0, FloorDiv(r[a] - block[a] - margin, block[a]) + 1);
      hi[a] = std::min<std::int64_t>(num_blocks[a] - 1, FloorDiv(r[a] + margin, block[a]));
    }
    const Index3 own = r.cwiseQuotient(block);
    for (std::int64_t bx = lo.x(); bx <= hi.x(); ++bx) {
      for (std::int64_t by = lo.y(); by <= hi.y(); ++by) {
        for (std::int64_t bz = lo.z(); bz <= hi.z(); ++bz) {
          Block& b = blocks[block_id(Index3(bx, by, bz))];
          b.voxels.push_back(key);
          if (Index3(bx, by, bz) == own) b.core.push_back(key);
        }
      }
    }
  }

  for (auto& [id, b] : blocks) {
    if (b.core.empty()) continue;
    const Index3 index(id / (num_blocks.y() * num_blocks.z()),
                       (id / num_blocks.z()) % num_blocks.y(), id % num_blocks.z());
    const VoxelKey origin =
        min_key + index.cwiseProduct(block).cast<int>() - VoxelKey::Constant(margin);
    SummedVolume table(block + Index3::Constant(2 * margin), origin);
    for (const VoxelKey& key : b.voxels) table.Add(key);
    table.Integrate();
    ++result.blocks;
    for (const VoxelKey& key : b.core) {
      if (IsCandidate(table, key, h, tau_change)) result.keys.push_back(key);
    }
    b = Block();  // release memory early
  }
  std::sort(result.keys.begin(), result.keys.end(), [](const VoxelKey& a, const VoxelKey& b) {
    return std::lexicographical_compare(a.data(), a.data() + 3, b.data(), b.data() + 3);
  });
  return result;
}

}  // namespace mapd::voxel::internal
