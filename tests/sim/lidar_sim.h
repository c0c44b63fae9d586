// A simulated spinning multi-beam LiDAR (Velodyne VLP-16-like) for the 3D
// plane benchmarks and tests (issue 10). Test support only: never linked into
// mapd. The sensor casts one ray per (beam, column) into a LidarWorld and
// returns an organised scan: points in the sensor frame (x forward, z up),
// row-major by beam then column, NaN where a ray has no return. Range noise is
// Gaussian and drawn from a generator seeded per scan, so Scan(pose, k) is a
// function of (params, world, pose, k).
#ifndef MAPD_TESTS_SIM_LIDAR_SIM_H_
#define MAPD_TESTS_SIM_LIDAR_SIM_H_

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "common/status.h"
#include "geometry/rigid3.h"

namespace mapd::sim {

struct LidarParams {
  int beams = 16;  // evenly spaced over [-vertical_half_fov, +vertical_half_fov]
  double vertical_half_fov_deg = 15.0;
  double horizontal_res_deg = 0.3;  // columns = round(360 / horizontal_res_deg)
  double rate_hz = 10.0;            // scans per second (sets the time between route poses)
  double min_range_m = 0.5;         // closer returns are dropped (the sensor housing)
  double max_range_m = 40.0;
  double range_sigma_m = 0.02;  // Gaussian range noise
  uint64_t seed = 1;
  // InvalidArgument naming the field when a value is out of range.
  Status Validate() const;
  int columns() const;
};

// What a ray hit: range along the unit ray and a label (world-specific: a
// structure index, -1 ground, -2 nothing).
struct RayHit {
  double range_m = 0.0;
  int label = -2;
};

class LidarWorld {
 public:
  virtual ~LidarWorld() = default;
  // First surface along origin + t * direction (unit), 0 < t <= max_range_m,
  // in the world frame; label -2 when nothing is hit.
  virtual RayHit Cast(const Eigen::Vector3d& origin, const Eigen::Vector3d& direction,
                      double max_range_m) const = 0;
};

struct LidarScan {
  int beams = 0;
  int columns = 0;
  std::vector<Eigen::Vector3f> points;  // sensor frame, beams * columns, NaN: no return
  std::vector<int> labels;              // per point, -2 for no return
  const Eigen::Vector3f& at(int beam, int column) const { return points[beam * columns + column]; }
  size_t valid_count() const;
};

class LidarSimulator {
 public:
  // REQUIRES: params.Validate().ok().
  explicit LidarSimulator(const LidarParams& params);
  // Scan number `index` from pose T_world_sensor; noise seeded by (seed, index).
  LidarScan Scan(const LidarWorld& world, const geometry::Rigid3& T_world_sensor,
                 uint64_t index) const;
  const LidarParams& params() const { return params_; }

 private:
  LidarParams params_;
  std::vector<Eigen::Vector3d> directions_;  // sensor frame, beams * columns
};

}  // namespace mapd::sim

#endif  // MAPD_TESTS_SIM_LIDAR_SIM_H_
