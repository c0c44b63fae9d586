#include "voxel/plane_regions.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <numeric>

namespace mapd::voxel::internal {
namespace {

// Running first and second moments of a region (voxel units, relative to the
// seed so that they stay small).
struct Moments {
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  Eigen::Matrix3d outer = Eigen::Matrix3d::Zero();
  int count = 0;

  void Add(const Eigen::Vector3d& p) {
    const Eigen::Vector3d d = p - origin;
    sum += d;
    outer += d * d.transpose();
    ++count;
  }
  FittedPlane Fit() const {
    FittedPlane plane;
    plane.size = count;
    if (count == 0) return plane;
    const Eigen::Vector3d mean = sum / count;
    const Eigen::Matrix3d cov = outer / count - mean * mean.transpose();
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen;
    eigen.computeDirect(cov);
    plane.normal = eigen.eigenvectors().col(0).normalized();
    plane.offset = -plane.normal.dot(mean + origin);
    plane.rms = std::sqrt(std::max(0.0, eigen.eigenvalues()(0)));
    return plane;
  }
};

Eigen::Vector3d Centre(const VoxelKey& key) {
  return key.cast<double>() + Eigen::Vector3d::Constant(0.5);
}

}  // namespace

FittedPlane FitPlane(const std::vector<Eigen::Vector3d>& points) {
  Moments m;
  if (!points.empty()) m.origin = points.front();
  for (const Eigen::Vector3d& p : points) m.Add(p);
  return m.Fit();
}

PlaneRegions GrowPlaneRegions(const std::vector<VoxelKey>& keys, const VoxelIndex& index,
                              const GridNormals& normals, const PlaneRegionParams& params) {
  const std::size_t n = keys.size();
  const float cos_smooth = static_cast<float>(std::cos(params.smoothness_deg * M_PI / 180.0));
  const float cos_region = static_cast<float>(std::cos(params.region_angle_deg * M_PI / 180.0));
  std::vector<int> order(n);
  std::iota(order.begin(), order.end(), 0);
  // Stable: ties (common, curvature is exactly 0 on ideal planes) keep key order.
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) {
    return normals.curvature[static_cast<std::size_t>(a)] <
           normals.curvature[static_cast<std::size_t>(b)];
  });

  PlaneRegions out;
  out.label.assign(n, -1);
  std::vector<int> visited(n, -1);  // region id that last looked at the voxel
  std::vector<int> queue, members;
  int region_id = 0;
  for (int seed : order) {
    const auto s = static_cast<std::size_t>(seed);
    if (normals.curvature[s] >= params.curvature_threshold) break;
    if (out.label[s] != -1 || visited[s] != -1) continue;
    const int id = region_id++;
    Moments moments;
    moments.origin = Centre(keys[s]);
    FittedPlane plane;
    plane.normal = normals.normals[s].cast<double>();
    plane.offset = -plane.normal.dot(moments.origin);
    int next_refit = 8;
    queue.assign(1, seed);
    members.assign(1, seed);
    visited[s] = id;
    moments.Add(Centre(keys[s]));
    for (std::size_t head = 0; head < queue.size(); ++head) {
      const auto p = static_cast<std::size_t>(queue[head]);
      const Eigen::Vector3f& np = normals.normals[p];
      index.ForEachInCube(keys[p], 1, [&](int q, const VoxelKey&) {
        const auto uq = static_cast<std::size_t>(q);
        if (visited[uq] == id || out.label[uq] != -1) return;
        const Eigen::Vector3f& nq = normals.normals[uq];
        if (std::abs(np.dot(nq)) < cos_smooth) return;
        if (std::abs(plane.normal.cast<float>().dot(nq)) < cos_region) return;
        const Eigen::Vector3d cq = Centre(keys[uq]);
        if (plane.Distance(cq) > params.max_plane_distance) return;
        visited[uq] = id;
        members.push_back(q);
        moments.Add(cq);
        if (normals.curvature[uq] < params.curvature_threshold) queue.push_back(q);
        if (moments.count >= next_refit) {
          plane = moments.Fit();
          next_refit *= 2;
        }
      });
    }
    if (static_cast<int>(members.size()) < params.min_region_size) continue;
    plane = moments.Fit();
    if (plane.rms > params.max_plane_rms) continue;
    const int label = static_cast<int>(out.planes.size());
    out.planes.push_back(plane);
    for (int m : members) out.label[static_cast<std::size_t>(m)] = label;
  }
  return out;
}

}  // namespace mapd::voxel::internal
