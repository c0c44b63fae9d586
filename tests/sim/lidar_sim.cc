#include "sim/lidar_sim.h"

#include <cmath>
#include <limits>
#include <random>
#include <string>

#include "common/param_check.h"

namespace mapd::sim {

Status LidarParams::Validate() const {
  if (beams < 2 || beams > 256) {
    return Status::InvalidArgument("lidar params: beams = " + std::to_string(beams) +
                                   " is outside [2, 256]");
  }
  MAPD_RETURN_IF_ERROR(
      CheckParamRange("lidar params", "vertical_half_fov_deg", vertical_half_fov_deg, 0.1, 89.0));
  MAPD_RETURN_IF_ERROR(
      CheckParamRange("lidar params", "horizontal_res_deg", horizontal_res_deg, 0.05, 10.0));
  MAPD_RETURN_IF_ERROR(CheckParamRange("lidar params", "rate_hz", rate_hz, 0.1, 100.0));
  MAPD_RETURN_IF_ERROR(CheckParamRange("lidar params", "min_range_m", min_range_m, 0.0, 10.0));
  MAPD_RETURN_IF_ERROR(
      CheckParamRange("lidar params", "max_range_m", max_range_m, min_range_m + 0.1, 1000.0));
  MAPD_RETURN_IF_ERROR(CheckParamRange("lidar params", "range_sigma_m", range_sigma_m, 0.0, 1.0));
  return Status::Ok();
}

int LidarParams::columns() const {
  return static_cast<int>(std::lround(360.0 / horizontal_res_deg));
}

size_t LidarScan::valid_count() const {
  size_t n = 0;
  for (const int l : labels) n += l != -2;
  return n;
}

LidarSimulator::LidarSimulator(const LidarParams& params) : params_(params) {
  const int columns = params_.columns();
  directions_.reserve(static_cast<size_t>(params_.beams) * columns);
  for (int b = 0; b < params_.beams; ++b) {
    const double elevation = (-params_.vertical_half_fov_deg +
                              2.0 * params_.vertical_half_fov_deg * b / (params_.beams - 1)) *
                             M_PI / 180.0;
    for (int c = 0; c < columns; ++c) {
      const double azimuth = -M_PI + (c + 0.5) * 2.0 * M_PI / columns;
      directions_.emplace_back(std::cos(elevation) * std::cos(azimuth),
                               std::cos(elevation) * std::sin(azimuth), std::sin(elevation));
    }
  }
}

LidarScan LidarSimulator::Scan(const LidarWorld& world, const geometry::Rigid3& T_world_sensor,
                               uint64_t index) const {
  LidarScan scan;
  scan.beams = params_.beams;
  scan.columns = params_.columns();
  const float nan = std::numeric_limits<float>::quiet_NaN();
  scan.points.assign(directions_.size(), Eigen::Vector3f(nan, nan, nan));
  scan.labels.assign(directions_.size(), -2);
  // splitmix-style mixing so neighbouring indices give unrelated streams.
  std::mt19937_64 rng(params_.seed * 0x9E3779B97F4A7C15ull + index * 0xBF58476D1CE4E5B9ull + 1);
  std::normal_distribution<double> noise(0.0, params_.range_sigma_m);
  const Eigen::Matrix3d R = T_world_sensor.rotation.toRotationMatrix();
  for (size_t i = 0; i < directions_.size(); ++i) {
    const RayHit hit =
        world.Cast(T_world_sensor.translation, R * directions_[i], params_.max_range_m);
    const double r = hit.range_m + (params_.range_sigma_m > 0 ? noise(rng) : 0.0);
    if (hit.label == -2 || r < params_.min_range_m || r > params_.max_range_m) continue;
    scan.points[i] = (directions_[i] * r).cast<float>();
    scan.labels[i] = hit.label;
  }
  return scan;
}

}  // namespace mapd::sim
