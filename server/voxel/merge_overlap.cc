#include "voxel/merge_overlap.h"

#include <algorithm>
#include <cmath>

namespace mapd::voxel {
namespace {

bool GridOccupiedNear(const VoxelGrid& grid, const VoxelKey& key) {
  if (grid.IsOccupied(key)) return true;
  for (int dx = -1; dx <= 1; ++dx) {
    for (int dy = -1; dy <= 1; ++dy) {
      for (int dz = -1; dz <= 1; ++dz) {
        if ((dx | dy | dz) == 0) continue;
        if (grid.IsOccupied(key + VoxelKey(dx, dy, dz))) return true;
      }
    }
  }
  return false;
}

template <typename Grid>
OverlapScore Score(const Grid& a, const VoxelGrid& a_grid, const VoxelGrid& b,
                   const Eigen::Isometry3d& T_a_b, std::size_t max_points) {
  OverlapScore out;
  const auto& centres = b.occupied_centres();
  if (centres.empty() || a_grid.empty()) return out;
  if (max_points > 0 && centres.size() > max_points)
    out.step = (centres.size() + max_points - 1) / max_points;
  for (std::size_t i = 0; i < centres.size(); i += out.step) {
    ++out.evaluated;
    const VoxelKey key = a_grid.PointToKey(T_a_b * centres[i]);
    if (a.OccupiedNear(key)) {
      ++out.observed;
      ++out.coinciding;
    } else if (a.Observed(key)) {
      ++out.observed;
    }
  }
  if (out.observed > 0)
    out.score = static_cast<double>(out.coinciding) / static_cast<double>(out.observed);
  return out;
}

// The grid itself, as Score's A.
struct GridSide {
  const VoxelGrid& grid;
  bool OccupiedNear(const VoxelKey& key) const { return GridOccupiedNear(grid, key); }
  bool Observed(const VoxelKey& key) const { return grid.State(key) != VoxelState::kUnknown; }
};

}  // namespace

OverlapIndex::OverlapIndex(const VoxelGrid& a, std::size_t max_cells) : grid_(&a) {
  if (a.empty()) return;
  VoxelKey lo = a.occupied_keys().front(), hi = lo;
  for (const VoxelKey& k : a.occupied_keys()) {
    lo = lo.cwiseMin(k);
    hi = hi.cwiseMax(k);
  }
  lo -= VoxelKey::Ones();  // the dilation's margin
  hi += VoxelKey::Ones();
  const VoxelKey size = hi - lo + VoxelKey::Ones();
  if (!near_.Reset(lo, size, max_cells)) return;
  // Observed: over every voxel A knows (free space reaches beyond the
  // occupied box) when that box fits, so that a point of B anywhere outside
  // it is unknown at once; else over the occupied box, the grid answering
  // outside it. Wrong alignments put most of B outside A's occupied box, and
  // there the grid's answer "unknown" costs a hash lookup per octree level.
  VoxelKey known_lo = lo, known_hi = hi;
  a.ForEachFreeCube([&](const VoxelKey& min_key, int edge) {
    known_lo = known_lo.cwiseMin(min_key);
    known_hi = known_hi.cwiseMax(min_key + VoxelKey::Constant(edge - 1));
  });
  observed_everywhere_ =
      observed_.Reset(known_lo, known_hi - known_lo + VoxelKey::Ones(), max_cells);
  if (!observed_everywhere_) observed_.Reset(lo, size, max_cells);
  const VoxelKey observed_hi = observed_.lo + observed_.size - VoxelKey::Ones();
  for (const VoxelKey& k : a.occupied_keys()) {
    for (int dx = -1; dx <= 1; ++dx) {
      for (int dy = -1; dy <= 1; ++dy) {
        for (int dz = -1; dz <= 1; ++dz) near_.Set(k + VoxelKey(dx, dy, dz));
      }
    }
    observed_.Set(k);
  }
  a.ForEachFreeCube([&](const VoxelKey& min_key, int edge) {
    // Only the part of the cube inside the box, a row along x at a time.
    const VoxelKey from = min_key.cwiseMax(observed_.lo);
    const VoxelKey to = (min_key + VoxelKey::Constant(edge - 1)).cwiseMin(observed_hi);
    if ((from.array() > to.array()).any()) return;
    for (int z = from.z(); z <= to.z(); ++z) {
      for (int y = from.y(); y <= to.y(); ++y) observed_.SetRow(VoxelKey(from.x(), y, z), to.x());
    }
  });
}

bool OverlapIndex::OccupiedNear(const VoxelKey& key) const {
  if (near_.empty()) return GridOccupiedNear(*grid_, key);
  return near_.Test(key);  // the box holds every occupied voxel's neighbours
}

bool OverlapIndex::Observed(const VoxelKey& key) const {
  if (!observed_.Contains(key)) {
    return !observed_everywhere_ && grid_->State(key) != VoxelState::kUnknown;
  }
  return observed_.Test(key);
}

OverlapScore ComputeOverlapScore(const VoxelGrid& a, const VoxelGrid& b,
                                 const Eigen::Isometry3d& T_a_b, std::size_t max_points) {
  return Score(GridSide{a}, a, b, T_a_b, max_points);
}

OverlapScore ComputeOverlapScore(const OverlapIndex& a, const VoxelGrid& b,
                                 const Eigen::Isometry3d& T_a_b, std::size_t max_points) {
  return Score(a, a.grid(), b, T_a_b, max_points);
}

namespace {

// The first multiple of `stride` at or above `v` (any sign).
int FirstMultiple(int v, int stride) {
  const int q = v / stride;
  const int down = (v % stride != 0 && v < 0) ? q - 1 : q;  // floor(v / stride)
  return down * stride == v ? v : (down + 1) * stride;
}

}  // namespace

SharedFree ComputeSharedFree(const OverlapIndex& a, const VoxelGrid& b,
                             const Eigen::Isometry3d& T_a_b, std::size_t max_points) {
  SharedFree out;
  double volume = 0;  // B's free voxels
  b.ForEachFreeCube([&](const VoxelKey&, int edge) { volume += std::pow(edge, 3.0); });
  if (volume == 0 || a.grid().empty()) return out;
  const double budget = static_cast<double>(
      max_points > 0 ? std::min(max_points, kMaxSharedFreePoints) : kMaxSharedFreePoints);
  if (volume > budget) out.stride = static_cast<int>(std::ceil(std::cbrt(volume / budget)));
  const int s = out.stride;
  const VoxelGrid& a_grid = a.grid();
  b.ForEachFreeCube([&](const VoxelKey& min_key, int edge) {
    VoxelKey from, to;
    for (int i = 0; i < 3; ++i) {
      from[i] = FirstMultiple(min_key[i], s);
      to[i] = min_key[i] + edge - 1;
    }
    for (int z = from.z(); z <= to.z(); z += s) {
      for (int y = from.y(); y <= to.y(); y += s) {
        for (int x = from.x(); x <= to.x(); x += s) {
          const VoxelKey key = a_grid.PointToKey(T_a_b * b.KeyToCentre(VoxelKey(x, y, z)));
          ++out.evaluated;
          if (a.Observed(key) && !a.OccupiedNear(key)) ++out.shared;
        }
      }
    }
  });
  return out;
}

}  // namespace mapd::voxel
