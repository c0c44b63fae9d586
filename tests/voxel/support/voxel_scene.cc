#include "voxel/support/voxel_scene.h"

#include <octomap/OcTree.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <sstream>

namespace mapd::testing {
namespace {

// Signed distance to the surface of an axis-aligned box: negative inside.
double SignedDistance(const SceneBox& box, const Eigen::Vector3d& p) {
  const Eigen::Vector3d centre = 0.5 * (box.min_m + box.max_m);
  const Eigen::Vector3d half = 0.5 * (box.max_m - box.min_m);
  const Eigen::Vector3d d = (p - centre).cwiseAbs() - half;
  const double outside = d.cwiseMax(0.0).norm();
  return outside > 0.0 ? outside : d.maxCoeff();
}

// Coordinates are shifted by kShift so that faces pass through the voxel
// centres of an axis-aligned 0.1 m grid: one voxel thick there.
constexpr double kShift = 0.05;

SceneBox Box(double x0, double y0, double z0, double x1, double y1, double z1, bool room = false) {
  return {Eigen::Vector3d(x0, y0, z0) + Eigen::Vector3d::Constant(kShift),
          Eigen::Vector3d(x1, y1, z1) + Eigen::Vector3d::Constant(kShift), room};
}

}  // namespace

SceneState StateAt(const VoxelScene& scene, const Eigen::Vector3d& p, double resolution_m) {
  const double w = scene.half_thickness_voxels * resolution_m;
  bool in_room = false, in_solid = false;
  for (const SceneBox& box : scene.boxes) {
    const double sd = SignedDistance(box, p);
    if (std::abs(sd) <= w) return SceneState::kOccupied;
    if (box.room && sd < 0) in_room = true;
    if (!box.room && sd < 0) in_solid = true;
  }
  return in_room && !in_solid ? SceneState::kFree : SceneState::kUnknown;
}

VoxelScene FurnishedRoom() {
  VoxelScene scene;
  scene.boxes = {
      Box(0.0, 0.0, 0.0, 9.0, 4.5, 2.5, true), Box(0.6, 0.5, 0.0, 1.8, 1.3, 0.9),  // table
      Box(2.4, 3.1, 0.0, 3.1, 4.5, 1.9),  // cupboard against the wall
      Box(3.7, 1.0, 0.0, 4.6, 1.6, 0.7),  // low chest
      Box(5.2, 2.3, 0.0, 6.4, 3.4, 1.2),  // desk
      Box(7.0, 0.0, 0.0, 8.1, 0.9, 1.5),  // shelf against the wall
      Box(7.6, 3.0, 0.0, 8.4, 3.8, 0.6),  // box
  };
  return scene;
}

VoxelScene OtherRoom() {
  VoxelScene scene;
  scene.boxes = {
      Box(20.0, 20.0, 0.0, 27.2, 25.6, 3.1, true),
      Box(21.0, 21.2, 0.0, 21.7, 23.5, 1.1),
      Box(23.3, 24.0, 0.0, 25.5, 25.6, 0.8),
      Box(25.8, 20.6, 0.0, 26.6, 21.9, 2.2),
  };
  return scene;
}

VoxelScene FlatWall() {
  VoxelScene scene;
  scene.boxes = {Box(0.0, 0.0, 0.0, 6.0, 0.2, 3.0)};
  return scene;
}

VoxelScene Grove() {
  VoxelScene scene;
  scene.boxes = {Box(0.0, 0.0, -2.0, 40.0, 40.0, 12.0, true)};
  // A fixed linear congruential sequence: the same grove on every platform.
  std::uint32_t state = 20261202;
  const auto unit = [&state] {
    state = state * 1664525U + 1013904223U;
    return static_cast<double>(state >> 8) / static_cast<double>(1U << 24);
  };
  // Uneven ground: 5 m terraces 0-0.8 m high (a flat ground would match
  // itself at any horizontal shift).
  for (int i = 0; i < 8; ++i) {
    for (int j = 0; j < 8; ++j) {
      scene.boxes.push_back(Box(5.0 * i, 5.0 * j, -1.5, 5.0 * i + 5, 5.0 * j + 5, 0.8 * unit()));
    }
  }
  for (int i = 0; i < 90; ++i) {
    const double x = 1.0 + 37.0 * unit(), y = 1.0 + 37.0 * unit();
    const double w = 0.4 + 1.2 * unit(), d = 0.4 + 1.2 * unit(), h = 0.5 + 4.5 * unit();
    scene.boxes.push_back(Box(x, y, 0.0, x + w, y + d, h));
  }
  return scene;
}

std::string RasteriseSubmap(const VoxelScene& scene, const Eigen::AlignedBox3d& crop_scene,
                            const Eigen::Isometry3d& T_scene_submap, double resolution_m) {
  octomap::OcTree tree(resolution_m);
  // The crop's box in the submap frame bounds the voxels to visit.
  const Eigen::Isometry3d T_submap_scene = T_scene_submap.inverse();
  Eigen::AlignedBox3d bounds;
  for (int c = 0; c < 8; ++c) {
    bounds.extend(T_submap_scene *
                  crop_scene.corner(static_cast<Eigen::AlignedBox3d::CornerType>(c)));
  }
  const Eigen::Vector3i lo = (bounds.min() / resolution_m).array().floor().cast<int>();
  const Eigen::Vector3i hi = (bounds.max() / resolution_m).array().floor().cast<int>();
  for (int x = lo.x(); x <= hi.x(); ++x) {
    for (int y = lo.y(); y <= hi.y(); ++y) {
      for (int z = lo.z(); z <= hi.z(); ++z) {
        const Eigen::Vector3d c =
            (Eigen::Vector3d(x, y, z) + Eigen::Vector3d::Constant(0.5)) * resolution_m;
        const Eigen::Vector3d p = T_scene_submap * c;
        if (!crop_scene.contains(p)) continue;
        const SceneState state = StateAt(scene, p, resolution_m);
        if (state == SceneState::kUnknown) continue;
        const octomap::OcTreeKey key = tree.coordToKey(octomap::point3d(
            static_cast<float>(c.x()), static_cast<float>(c.y()), static_cast<float>(c.z())));
        tree.setNodeValue(key,
                          state == SceneState::kOccupied ? tree.getClampingThresMaxLog()
                                                         : tree.getClampingThresMinLog(),
                          true);
      }
    }
  }
  tree.updateInnerOccupancy();
  tree.prune();
  std::stringstream out;
  tree.writeBinaryConst(out);
  return out.str();
}

Eigen::Isometry3d Pose(double yaw_deg, double pitch_deg, double roll_deg,
                       const Eigen::Vector3d& t) {
  const double k = M_PI / 180.0;
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = (Eigen::AngleAxisd(yaw_deg * k, Eigen::Vector3d::UnitZ()) *
                Eigen::AngleAxisd(pitch_deg * k, Eigen::Vector3d::UnitY()) *
                Eigen::AngleAxisd(roll_deg * k, Eigen::Vector3d::UnitX()))
                   .toRotationMatrix();
  T.translation() = t;
  return T;
}

Eigen::AlignedBox3d RoomCropX(double x0, double x1) {
  return Eigen::AlignedBox3d(Eigen::Vector3d(x0, -1.0, -1.0), Eigen::Vector3d(x1, 5.5, 3.5));
}

}  // namespace mapd::testing
