#include "client/support/room_octree.h"

#include <cmath>
#include <sstream>
#include <vector>

#include <octomap/OcTree.h>

namespace mapd::testing {
namespace {

using Points = std::vector<Eigen::Vector3d>;

// An axis-aligned box's side faces, and its top and bottom if asked, sampled
// every `step` metres.
void AddBoxSurface(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, double step, bool with_top,
                   bool with_bottom, Points* out) {
  auto count = [step](double a, double b) { return std::max(1, static_cast<int>(std::round((b - a) / step))); };
  const int nx = count(lo.x(), hi.x()), ny = count(lo.y(), hi.y()), nz = count(lo.z(), hi.z());
  auto lerp = [](double a, double b, int i, int n) { return a + (b - a) * i / n; };
  for (int i = 0; i <= nx; ++i) {
    for (int j = 0; j <= ny; ++j) {
      const double x = lerp(lo.x(), hi.x(), i, nx), y = lerp(lo.y(), hi.y(), j, ny);
      if (with_top) out->push_back({x, y, hi.z()});
      if (with_bottom) out->push_back({x, y, lo.z()});
    }
  }
  for (int k = 0; k <= nz; ++k) {
    const double z = lerp(lo.z(), hi.z(), k, nz);
    for (int i = 0; i <= nx; ++i) {
      const double x = lerp(lo.x(), hi.x(), i, nx);
      out->push_back({x, lo.y(), z});
      out->push_back({x, hi.y(), z});
    }
    for (int j = 0; j <= ny; ++j) {
      const double y = lerp(lo.y(), hi.y(), j, ny);
      out->push_back({lo.x(), y, z});
      out->push_back({hi.x(), y, z});
    }
  }
}

// Floor, four 2 m walls of an 8 m x 6 m room without a ceiling (a top view
// must show the inside), four boxes of different sizes (an asymmetric scene,
// so that only one transform matches).
Points RoomSurface(double step, double half_voxel) {
  Points points;
  const double h = half_voxel;  // surfaces sit on voxel centres, not on faces
  for (double x = h; x <= 8.0 - h + 1e-9; x += step) {
    for (double y = h; y <= 6.0 - h + 1e-9; y += step) points.push_back({x, y, h});
  }
  AddBoxSurface({h, h, h}, {8.0 - h, 6.0 - h, 2.0 - h}, step, /*with_top=*/false, /*with_bottom=*/false, &points);
  AddBoxSurface({1.5 + h, 1.0 + h, h}, {2.5 + h, 2.2 + h, 1.0 + h}, step, true, false, &points);
  AddBoxSurface({4.0 + h, 4.2 + h, h}, {4.8 + h, 5.0 + h, 0.6 + h}, step, true, false, &points);
  AddBoxSurface({5.5 + h, 1.0 + h, h}, {6.7 + h, 1.8 + h, 0.8 + h}, step, true, false, &points);
  AddBoxSurface({6.3 + h, 3.5 + h, h}, {7.1 + h, 4.9 + h, 1.4 + h}, step, true, false, &points);
  return points;
}

std::string ToBt(const Points& points, const Eigen::Vector3d& sensor, double resolution) {
  octomap::OcTree tree(resolution);
  octomap::Pointcloud cloud;
  for (const Eigen::Vector3d& p : points) {
    cloud.push_back(static_cast<float>(p.x()), static_cast<float>(p.y()), static_cast<float>(p.z()));
  }
  tree.insertPointCloud(cloud, octomap::point3d(static_cast<float>(sensor.x()), static_cast<float>(sensor.y()),
                                                static_cast<float>(sensor.z())));
  tree.updateInnerOccupancy();
  tree.toMaxLikelihood();
  tree.prune();
  std::stringstream out;
  tree.writeBinary(out);
  return out.str();
}

}  // namespace

RoomMaps MakeRoomMaps(const RoomMapsOptions& options) {
  const double res = options.resolution_m;
  RoomMaps maps;
  maps.T_a_b = Eigen::Translation3d(options.translation_m) *
               Eigen::AngleAxisd(options.yaw_deg * M_PI / 180.0, Eigen::Vector3d::UnitZ());
  const Points room = RoomSurface(res / 2, res / 2);
  const Eigen::Vector3d sensor_a(4.0, 3.0, 1.2);
  maps.a_bt = ToBt(room, sensor_a, res);

  const Eigen::Isometry3d T_b_a = maps.T_a_b.inverse();
  Points crop;
  for (const Eigen::Vector3d& p : room) {
    if (p.x() >= options.crop_x_min_m) crop.push_back(T_b_a * p);
  }
  const Eigen::Vector3d sensor_b = T_b_a * Eigen::Vector3d(5.5, 3.0, 1.2);
  maps.b_bt = ToBt(crop, sensor_b, res);

  Points floor;
  for (double x = res / 2; x < 4.0; x += res / 2) {
    for (double y = res / 2; y < 4.0; y += res / 2) floor.push_back({x, y, res / 2});
  }
  maps.floor_bt = ToBt(floor, {2.0, 2.0, 1.0}, res);
  return maps;
}

}  // namespace mapd::testing
