#include "voxel/corner_faces.h"

#include <Eigen/Dense>
#include <cmath>

namespace mapd::voxel::internal {
namespace {

// The voxels of each face within the support radius of `x`.
std::array<std::vector<Eigen::Vector3d>, 3> FaceVoxels(const std::vector<VoxelKey>& keys,
                                                       const VoxelIndex& index,
                                                       const std::array<FittedPlane, 3>& planes,
                                                       const Eigen::Vector3d& x,
                                                       const FaceParams& params) {
  std::array<std::vector<Eigen::Vector3d>, 3> faces;
  const VoxelKey centre = x.array().floor().cast<int>().matrix();
  const int h = static_cast<int>(std::ceil(params.support_radius)) + 1;
  const double r2 = params.support_radius * params.support_radius;
  index.ForEachInCube(centre, h, [&](int i, const VoxelKey&) {
    const Eigen::Vector3d p =
        keys[static_cast<std::size_t>(i)].cast<double>() + Eigen::Vector3d::Constant(0.5);
    if ((p - x).squaredNorm() > r2) return;
    int face = -1;
    for (int k = 0; k < 3; ++k) {
      if (planes[static_cast<std::size_t>(k)].Distance(p) > params.band) continue;
      if (face != -1) return;  // on an edge: near two planes
      face = k;
    }
    if (face >= 0) faces[static_cast<std::size_t>(face)].push_back(p);
  });
  return faces;
}

}  // namespace

bool IntersectPlanes(const std::array<FittedPlane, 3>& planes, double min_determinant,
                     Eigen::Vector3d* point) {
  Eigen::Matrix3d n;
  Eigen::Vector3d d;
  for (int k = 0; k < 3; ++k) {
    n.row(k) = planes[static_cast<std::size_t>(k)].normal.transpose();
    d(k) = -planes[static_cast<std::size_t>(k)].offset;
  }
  if (!(std::abs(n.determinant()) >= min_determinant)) return false;
  *point = n.colPivHouseholderQr().solve(d);
  return point->allFinite();
}

bool FacesMeet(const std::vector<VoxelKey>& keys, const VoxelIndex& index,
               const std::array<FittedPlane, 3>& planes, const FaceParams& params,
               MeetingFaces* faces) {
  std::array<FittedPlane, 3> current = planes;
  Eigen::Vector3d x;
  if (!IntersectPlanes(current, params.min_determinant, &x)) return false;
  const double min_cos_tilt = std::cos(params.max_refine_tilt_deg * M_PI / 180.0);
  for (int iteration = 0;; ++iteration) {
    const std::array<std::vector<Eigen::Vector3d>, 3> voxels =
        FaceVoxels(keys, index, current, x, params);
    std::array<FittedPlane, 3> local;
    for (std::size_t k = 0; k < 3; ++k) {
      if (static_cast<int>(voxels[k].size()) < params.min_support) return false;
      local[k] = FitPlane(voxels[k]);
    }
    if (iteration == params.refine_iterations) {
      faces->position = x;
      faces->planes = current;
      for (std::size_t k = 0; k < 3; ++k) {
        Eigen::Vector3d mean = Eigen::Vector3d::Zero();
        for (const Eigen::Vector3d& p : voxels[k]) mean += p;
        faces->face_mean[k] = mean / static_cast<double>(voxels[k].size());
        faces->support[k] = static_cast<int>(voxels[k].size());
      }
      return true;
    }
    // Local refit: only faces whose local voxels still look like that plane.
    std::array<FittedPlane, 3> refined = current;
    for (std::size_t k = 0; k < 3; ++k) {
      if (std::abs(local[k].normal.dot(planes[k].normal)) >= min_cos_tilt) refined[k] = local[k];
    }
    Eigen::Vector3d y;
    if (!IntersectPlanes(refined, params.min_determinant, &y)) return false;
    current = refined;
    x = y;
  }
}

}  // namespace mapd::voxel::internal
