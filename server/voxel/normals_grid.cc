#include "voxel/normals_grid.h"

#include <Eigen/Eigenvalues>
#include <cmath>

namespace mapd::voxel::internal {

GridNormals ComputeGridNormals(const std::vector<VoxelKey>& keys, const VoxelIndex& index,
                               double radius_voxels) {
  GridNormals out;
  out.normals.assign(keys.size(), Eigen::Vector3f::UnitZ());
  out.curvature.assign(keys.size(), 1.0f);
  const int h = static_cast<int>(std::floor(radius_voxels));
  const int r2 = static_cast<int>(std::floor(radius_voxels * radius_voxels));
  for (std::size_t i = 0; i < keys.size(); ++i) {
    // Integer moments of the offsets: exact, and independent of where the
    // map lies (no cancellation for keys far from the origin).
    long n = 0, sx = 0, sy = 0, sz = 0, xx = 0, xy = 0, xz = 0, yy = 0, yz = 0, zz = 0;
    index.ForEachInCube(keys[i], h, [&](int, const VoxelKey& o) {
      if (o.squaredNorm() > r2) return;
      ++n;
      sx += o.x(), sy += o.y(), sz += o.z();
      xx += o.x() * o.x(), xy += o.x() * o.y(), xz += o.x() * o.z();
      yy += o.y() * o.y(), yz += o.y() * o.z(), zz += o.z() * o.z();
    });
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
