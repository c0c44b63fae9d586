#include "voxel/normals_grid.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <tuple>

namespace mapd::voxel::internal {

GridNormals ComputeGridNormals(const std::vector<VoxelKey>& keys, const VoxelIndex& index,
                               double radius_voxels) {
  GridNormals out;
  out.normals.assign(keys.size(), Eigen::Vector3f::UnitZ());
  out.curvature.assign(keys.size(), 1.0f);
  const int h = static_cast<int>(std::floor(radius_voxels));
  const int r2 = static_cast<int>(std::floor(radius_voxels * radius_voxels));
  // Voxels brick by brick: a brick's voxels read one dense window (the brick
  // grown by h) filled once from its neighbour bricks, instead of up to
  // eight brick look-ups and a cube scan per voxel; only the ball's offsets
  // are tested. The sums are the same integers in any order.
  constexpr int kBrickBits = VoxelIndex::kBrickBits;
  const int edge = VoxelIndex::kBrick + 2 * h;
  struct Offset {
    int x, y, z;
    std::ptrdiff_t at;  // in the window
  };
  std::vector<Offset> ball;
  for (int x = -h; x <= h; ++x) {
    for (int y = -h; y <= h; ++y) {
      for (int z = -h; z <= h; ++z) {
        if (x * x + y * y + z * z <= r2) ball.push_back({x, y, z, (x * edge + y) * edge + z});
      }
    }
  }
  const auto brick_of = [](const VoxelKey& k) -> VoxelKey {
    return {k.x() >> kBrickBits, k.y() >> kBrickBits, k.z() >> kBrickBits};
  };
  std::vector<std::uint32_t> order(keys.size());
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = static_cast<std::uint32_t>(i);
  std::sort(order.begin(), order.end(), [&](std::uint32_t p, std::uint32_t q) {
    const VoxelKey a = brick_of(keys[p]), b = brick_of(keys[q]);
    return std::tie(a.x(), a.y(), a.z(), p) < std::tie(b.x(), b.y(), b.z(), q);
  });
  std::vector<std::uint8_t> window(static_cast<std::size_t>(edge) * edge * edge);
  VoxelKey filled_brick = VoxelKey::Zero();  // set at k == 0
  for (std::size_t k = 0; k < order.size(); ++k) {
    const std::size_t i = order[k];
    const VoxelKey brick = brick_of(keys[i]);
    const VoxelKey lo = brick * VoxelIndex::kBrick - VoxelKey::Constant(h);
    if (k == 0 || brick != filled_brick) {
      index.FillOccupancy(lo, edge, window.data());
      filled_brick = brick;
    }
    const VoxelKey local = keys[i] - lo;
    const std::uint8_t* centre = window.data() + (local.x() * edge + local.y()) * edge + local.z();
    // Integer moments of the offsets: exact, and independent of where the
    // map lies (no cancellation for keys far from the origin).
    long n = 0, sx = 0, sy = 0, sz = 0, xx = 0, xy = 0, xz = 0, yy = 0, yz = 0, zz = 0;
    for (const Offset& o : ball) {
      if (centre[o.at] == 0) continue;
      ++n;
      sx += o.x, sy += o.y, sz += o.z;
      xx += o.x * o.x, xy += o.x * o.y, xz += o.x * o.z;
      yy += o.y * o.y, yz += o.y * o.z, zz += o.z * o.z;
    }
    if (n < 3) continue;
    const double inv = 1.0 / static_cast<double>(n);
    const Eigen::Vector3d mean(sx * inv, sy * inv, sz * inv);
    Eigen::Matrix3d c;
    c << xx * inv, xy * inv, xz * inv, xy * inv, yy * inv, yz * inv, xz * inv, yz * inv, zz * inv;
    c -= mean * mean.transpose();
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen;
    eigen.computeDirect(c);
    const Eigen::Vector3d lambda = eigen.eigenvalues().cwiseMax(0.0);
    const double sum = lambda.sum();
    out.normals[i] = eigen.eigenvectors().col(0).normalized().cast<float>();
    out.curvature[i] = sum > 0.0 ? static_cast<float>(lambda(0) / sum) : 1.0f;
  }
  return out;
}

}  // namespace mapd::voxel::internal
