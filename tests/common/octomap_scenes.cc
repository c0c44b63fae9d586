#include "common/octomap_scenes.h"

#include <octomap/OcTree.h>

#include <cmath>
#include <random>
#include <sstream>
#include <vector>

namespace mapd::testing {
namespace {

struct Box {
  Eigen::Vector3d min, max;  // metres, map frame
};

// Boxes of different sizes, none alike, so that corner constellations are unique.
std::vector<Box> Furniture(const RoomScene& s) {
  if (s.box_seed == 0) {
    return {{{1.0, 1.0, 0}, {2.2, 1.6, 0.8}}, {{3.0, 4.5, 0}, {3.8, 6.0, 1.2}},
            {{4.4, 1.2, 0}, {5.9, 2.0, 0.5}}, {{5.2, 5.5, 0}, {5.8, 6.1, 1.9}},
            {{6.8, 3.0, 0}, {8.0, 3.9, 1.0}}, {{8.5, 6.0, 0}, {9.5, 7.5, 0.7}},
            {{2.0, 3.0, 0}, {2.5, 3.9, 1.5}}};
  }
  std::mt19937 rng(s.box_seed);
  std::uniform_real_distribution<double> x(0.5, s.size_x_m - 2.0), y(0.5, s.size_y_m - 2.0),
      side(0.4, 1.4), h(0.4, 1.8);
  std::vector<Box> boxes;
  for (int i = 0; i < 7; ++i) {
    const Eigen::Vector3d lo(std::round(x(rng) * 10) / 10, std::round(y(rng) * 10) / 10, 0);
    boxes.push_back(
        {lo, lo + Eigen::Vector3d(std::round(side(rng) * 10) / 10, std::round(side(rng) * 10) / 10,
                                  std::round(h(rng) * 10) / 10)});
  }
  return boxes;
}

bool Inside(const Box& b, const Eigen::Vector3d& p) {
  return (p.array() > b.min.array()).all() && (p.array() < b.max.array()).all();
}

// Voxel (i, j, k) of the room: +1 occupied, -1 free, 0 nothing.
int Classify(const RoomScene& s, const std::vector<Box>& boxes, int i, int j, int k, int nx, int ny,
             int nz) {
  if (k == 0) return 1;  // floor
  if (s.floor_only) return 0;
  if (i == 0 || j == 0 || i == nx - 1 || j == ny - 1) return 1;  // walls
  const double r = s.resolution_m;
  const Eigen::Vector3d c((i + 0.5) * r, (j + 0.5) * r, (k + 0.5) * r);
  for (const Box& b : boxes) {
    if (!Inside(b, c)) continue;
    // Only the box's surface shell is occupied; its inside is never seen.
    const Eigen::Vector3d lo = c - Eigen::Vector3d::Constant(r),
                          hi = c + Eigen::Vector3d::Constant(r);
    return (Inside(b, lo) && Inside(b, hi)) ? 0 : 1;
  }
  return (s.with_free && k < nz - 1) ? -1 : 0;
}

}  // namespace

Eigen::Isometry3d YawTranslation(double yaw_rad, const Eigen::Vector3d& t_m) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::AngleAxisd(yaw_rad, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  T.translation() = t_m;
  return T;
}

std::string RoomSubmap(const RoomScene& s, double x_min_m, double x_max_m,
                       const Eigen::Isometry3d& T_map_submap, bool full_format) {
  const double r = s.resolution_m;
  const int nx = static_cast<int>(std::lround(s.size_x_m / r));
  const int ny = static_cast<int>(std::lround(s.size_y_m / r));
  const int nz = static_cast<int>(std::lround(s.height_m / r));
  const std::vector<Box> boxes = s.with_boxes ? Furniture(s) : std::vector<Box>{};
  const Eigen::Isometry3d T_submap_map = T_map_submap.inverse();
  octomap::OcTree tree(r);
  for (int i = 0; i < nx; ++i) {
    const double x = (i + 0.5) * r;
    if (x < x_min_m || x >= x_max_m) continue;
    for (int j = 0; j < ny; ++j) {
      for (int k = 0; k < nz; ++k) {
        const int c = Classify(s, boxes, i, j, k, nx, ny, nz);
        if (c == 0) continue;
        const Eigen::Vector3d p = T_submap_map * Eigen::Vector3d(x, (j + 0.5) * r, (k + 0.5) * r);
        tree.updateNode(octomap::point3d(static_cast<float>(p.x()), static_cast<float>(p.y()),
                                         static_cast<float>(p.z())),
                        c > 0);
      }
    }
  }
  tree.updateInnerOccupancy();
  std::ostringstream out;
  if (full_format) {
    tree.write(out);
  } else {
    tree.prune();
    tree.writeBinary(out);
  }
  return out.str();
}

}  // namespace mapd::testing
