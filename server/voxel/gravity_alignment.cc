#include "voxel/gravity_alignment.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <optional>
#include <string>

#include "voxel/corner_voxel_index.h"
#include "voxel/normals_grid.h"
#include "voxel/plane_regions.h"

namespace mapd::voxel {
namespace {

constexpr double kDeg = M_PI / 180.0;

// Weighted mean of the normals (signs turned towards `towards`) within
// max_angle_deg of it; zero when none.
Eigen::Vector3d MeanNormal(const std::vector<internal::FittedPlane>& planes,
                           const Eigen::Vector3d& towards, double max_angle_deg, int min_size,
                           int* count) {
  const double min_cos = std::cos(max_angle_deg * kDeg);
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  *count = 0;
  for (const auto& plane : planes) {
    if (plane.size < min_size) continue;
    const double c = plane.normal.dot(towards);
    if (std::abs(c) < min_cos) continue;
    sum += (c < 0 ? -1.0 : 1.0) * plane.size * plane.normal;
    ++*count;
  }
  return sum;
}

// The unit vector u (sign towards `up`) that minimises
//   sum_floors size (1 - (n.u)^2) + sum_walls size (n.u)^2
// over the planes within floor_deg of `up` (floors, ceilings) and within
// wall_deg of perpendicular to it (walls): the smallest eigenvector of
// sum_walls size n n^T - sum_floors size n n^T. `up` when no wall qualifies.
Eigen::Vector3d UpFromFloorsAndWalls(const std::vector<internal::FittedPlane>& planes,
                                     const Eigen::Vector3d& up, double floor_deg, double wall_deg,
                                     int min_size) {
  const double floor_cos = std::cos(floor_deg * kDeg);
  const double wall_sin = std::sin(wall_deg * kDeg);
  Eigen::Matrix3d scatter = Eigen::Matrix3d::Zero();
  int walls = 0;
  for (const auto& plane : planes) {
    if (plane.size < min_size) continue;
    const double c = std::abs(plane.normal.dot(up));
    const Eigen::Matrix3d nn = plane.size * plane.normal * plane.normal.transpose();
    if (c >= floor_cos) {
      scatter -= nn;
    } else if (c <= wall_sin) {
      scatter += nn;
      ++walls;
    }
  }
  if (walls == 0) return up;
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(scatter);
  const Eigen::Vector3d u = solver.eigenvectors().col(0).normalized();  // smallest eigenvalue
  return u.dot(up) < 0 ? Eigen::Vector3d(-u) : u;
}

// Circular Gaussian smoothing of a histogram.
std::vector<double> Smooth(const std::vector<double>& h, double sigma_bins) {
  if (sigma_bins <= 0) return h;
  const int n = static_cast<int>(h.size());
  const int radius = std::min(n / 2, static_cast<int>(std::ceil(3 * sigma_bins)));
  std::vector<double> out(h.size(), 0.0);
  for (int i = 0; i < n; ++i) {
    for (int d = -radius; d <= radius; ++d) {
      const double w = std::exp(-0.5 * d * d / (sigma_bins * sigma_bins));
      out[static_cast<std::size_t>(i)] += w * h[static_cast<std::size_t>(((i + d) % n + n) % n)];
    }
  }
  return out;
}

}  // namespace

Status GravityParams::Validate() const {
  if (!(max_up_tilt_deg > 0 && max_up_tilt_deg < 90) ||
      !(refine_up_deg > 0 && refine_up_deg < 90)) {
    return Status::InvalidArgument("gravity: max_up_tilt_deg and refine_up_deg must be in (0, 90)");
  }
  if (!(max_wall_tilt_deg > 0 && max_wall_tilt_deg < 90)) {
    return Status::InvalidArgument("gravity: max_wall_tilt_deg must be in (0, 90)");
  }
  if (!(bin_deg >= 0.05 && bin_deg <= 10) || !(smoothing_deg >= 0 && smoothing_deg <= 30)) {
    return Status::InvalidArgument(
        "gravity: bin_deg must be in [0.05, 10] and smoothing_deg in [0, 30]");
  }
  if (yaw_peaks < 1 || yaw_peaks > 8) {
    return Status::InvalidArgument("gravity: yaw_peaks must be in [1, 8]");
  }
  if (wall_up_rounds < 0 || wall_up_rounds > 10) {
    return Status::InvalidArgument("gravity: wall_up_rounds must be in [0, 10]");
  }
  if (!(min_peak_separation_deg >= 0 && min_peak_separation_deg <= 90) || min_plane_voxels < 3) {
    return Status::InvalidArgument(
        "gravity: min_peak_separation_deg must be in [0, 90] and min_plane_voxels >= 3");
  }
  return Status::Ok();
}

StatusOr<GravityFrame> EstimateGravityFrame(const VoxelGrid& grid, const GravityParams& params,
                                            const internal::GridSurface* surface) {
  MAPD_RETURN_IF_ERROR(params.Validate());
  const std::vector<VoxelKey>& keys = grid.occupied_keys();
  std::optional<internal::GridSurface> own;
  if (surface == nullptr || surface->radius_voxels != kGravityNormalRadiusVoxels) {
    surface = &own.emplace(keys, kGravityNormalRadiusVoxels);
  }
  const internal::VoxelIndex& index = surface->index;
  const internal::GridNormals& normals = surface->normals;
  // The corner extractor's other defaults (corner_extraction.h).
  internal::PlaneRegionParams region_params;
  region_params.smoothness_deg = 15.0;
  region_params.region_angle_deg = 18.0;
  region_params.curvature_threshold = 0.25;
  region_params.max_plane_distance = 2.0;
  region_params.max_plane_rms = 1.2;
  region_params.min_region_size = params.min_plane_voxels;
  const internal::PlaneRegions regions =
      internal::GrowPlaneRegions(keys, index, normals, region_params);

  GravityFrame frame;
  Eigen::Vector3d up = MeanNormal(regions.planes, Eigen::Vector3d::UnitZ(), params.max_up_tilt_deg,
                                  params.min_plane_voxels, &frame.floor_planes);
  if (frame.floor_planes == 0 || up.norm() == 0) {
    return Status::FailedPrecondition("no floor or ceiling plane within " +
                                      std::to_string(params.max_up_tilt_deg) + " deg of vertical");
  }
  up.normalize();
  const Eigen::Vector3d refined = MeanNormal(regions.planes, up, params.refine_up_deg,
                                             params.min_plane_voxels, &frame.floor_planes);
  if (refined.norm() > 0) up = refined.normalized();
  for (int round = 0; round < params.wall_up_rounds; ++round) {
    up = UpFromFloorsAndWalls(regions.planes, up, params.refine_up_deg, params.max_wall_tilt_deg,
                              params.min_plane_voxels);
  }
  frame.up = up;
  frame.R_up = Eigen::Quaterniond::FromTwoVectors(up, Eigen::Vector3d::UnitZ()).toRotationMatrix();

  const int bins = static_cast<int>(std::lround(180.0 / params.bin_deg));
  std::vector<double> histogram(static_cast<std::size_t>(bins), 0.0);
  const double max_vertical = std::sin(params.max_wall_tilt_deg * kDeg);
  for (const auto& plane : regions.planes) {
    if (plane.size < params.min_plane_voxels) continue;
    const Eigen::Vector3d n = frame.R_up * plane.normal;
    if (std::abs(n.z()) > max_vertical) continue;
    double angle = std::atan2(n.y(), n.x()) / kDeg;  // (-180, 180]
    angle = std::fmod(angle + 360.0, 180.0);
    const int bin = std::min(bins - 1, static_cast<int>(angle / params.bin_deg));
    histogram[static_cast<std::size_t>(bin)] += plane.size;
    ++frame.wall_planes;
  }
  if (frame.wall_planes == 0) {
    return Status::FailedPrecondition("no vertical wall plane to take the yaw from");
  }
  frame.wall_histogram = Smooth(histogram, params.smoothing_deg / params.bin_deg);
  return frame;
}

std::vector<double> YawCandidates(const GravityFrame& a, const GravityFrame& b,
                                  const GravityParams& params) {
  const std::vector<double>& ha = a.wall_histogram;
  const std::vector<double>& hb = b.wall_histogram;
  const int n = static_cast<int>(ha.size());
  if (n == 0 || hb.size() != ha.size()) return {};
  // c[k]: b's walls turned by k bins onto a's (b's bin i lands on bin i + k).
  std::vector<double> c(static_cast<std::size_t>(n), 0.0);
  for (int k = 0; k < n; ++k) {
    double sum = 0;
    for (int i = 0; i < n; ++i) {
      sum += ha[static_cast<std::size_t>((i + k) % n)] * hb[static_cast<std::size_t>(i)];
    }
    c[static_cast<std::size_t>(k)] = sum;
  }
  auto at = [&](int k) { return c[static_cast<std::size_t>(((k % n) + n) % n)]; };
  std::vector<std::pair<double, double>> peaks;  // (height, yaw deg)
  for (int k = 0; k < n; ++k) {
    const double l = at(k - 1), m = at(k), r = at(k + 1);
    if (m <= 0 || m < l || m < r || (m == l && m == r)) continue;
    // Parabolic interpolation between the bins.
    const double denominator = l - 2 * m + r;
    const double offset = denominator < 0 ? 0.5 * (l - r) / denominator : 0.0;
    peaks.emplace_back(m, (k + offset) * params.bin_deg);
  }
  std::sort(peaks.begin(), peaks.end(), [](const auto& x, const auto& y) { return x > y; });
  std::vector<double> kept_deg;
  for (const auto& peak : peaks) {
    if (static_cast<int>(kept_deg.size()) >= params.yaw_peaks) break;
    bool near = false;
    for (double kept : kept_deg) {
      const double d = std::abs(std::remainder(peak.second - kept, 180.0));
      near = near || d < params.min_peak_separation_deg;
    }
    if (!near) kept_deg.push_back(peak.second);
  }
  std::vector<double> yaws;
  for (double deg : kept_deg) {
    yaws.push_back(std::remainder(deg, 360.0) * kDeg);
    yaws.push_back(std::remainder(deg + 180.0, 360.0) * kDeg);
  }
  return yaws;
}

}  // namespace mapd::voxel
