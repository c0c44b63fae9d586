#include "sim/octomap_world.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>

namespace mapd::sim {
namespace {

octomap::point3d ToOcto(const Eigen::Vector3d& v) {
  return {static_cast<float>(v.x()), static_cast<float>(v.y()), static_cast<float>(v.z())};
}

bool KnownFree(const octomap::OcTree& tree, const octomap::point3d& p) {
  const octomap::OcTreeNode* node = tree.search(p);
  return node != nullptr && !tree.isNodeOccupied(node);
}

}  // namespace

double EstimateFloorZ(const octomap::OcTree& tree) {
  double x0, y0, z0, x1, y1, z1;
  tree.getMetricMin(x0, y0, z0);
  tree.getMetricMax(x1, y1, z1);
  const double res = tree.getResolution();
  std::vector<size_t> layers(static_cast<size_t>((z1 - z0) / res) + 1, 0);
  for (auto it = tree.begin_leafs(), end = tree.end_leafs(); it != end; ++it) {
    if (!tree.isNodeOccupied(*it) || it.getZ() > 0.5 * (z0 + z1)) continue;
    // A pruned leaf spans several layers: count it in each, by its footprint.
    const double size = it.getSize();
    const double weight = (size / res) * (size / res);
    for (double z = it.getZ() - 0.5 * size + 0.5 * res; z < it.getZ() + 0.5 * size; z += res) {
      const size_t layer =
          std::min(layers.size() - 1, static_cast<size_t>(std::max(0.0, (z - z0) / res)));
      layers[layer] += static_cast<size_t>(weight);
    }
  }
  const size_t best =
      static_cast<size_t>(std::max_element(layers.begin(), layers.end()) - layers.begin());
  return z0 + (static_cast<double>(best) + 0.5) * res;
}

RayHit OctoMapWorld::Cast(const Eigen::Vector3d& origin, const Eigen::Vector3d& direction,
                          double max_range_m) const {
  const octomap::point3d o = ToOcto(origin);
  const octomap::point3d d = ToOcto(direction);
  octomap::point3d centre;
  if (!tree_.castRay(o, d, centre, /*ignoreUnknownCells=*/true, max_range_m)) return {};
  octomap::point3d entry;
  double range = (centre - o).norm();
  if (tree_.getRayIntersection(o, d, centre, entry)) range = (entry - o).norm();
  if (range > max_range_m) return {};
  return {range, 0};
}

std::vector<geometry::Rigid3> SampleFreePoses(const octomap::OcTree& tree,
                                              const PoseSamplingParams& params) {
  std::vector<octomap::point3d> free;
  for (auto it = tree.begin_leafs(), end = tree.end_leafs(); it != end; ++it) {
    if (!tree.isNodeOccupied(*it)) free.push_back(it.getCoordinate());
  }
  const double floor_z = EstimateFloorZ(tree);
  std::mt19937_64 rng(params.seed);
  std::shuffle(free.begin(), free.end(), rng);
  std::uniform_real_distribution<double> yaw(-M_PI, M_PI);
  const float c = static_cast<float>(params.clearance_m);
  const octomap::point3d offsets[] = {{c, 0, 0},  {-c, 0, 0}, {0, c, 0},
                                      {0, -c, 0}, {0, 0, c},  {0, 0, -c}};
  std::vector<octomap::point3d> accepted;
  for (const octomap::point3d& p : free) {
    if (accepted.size() >= params.count) break;
    bool clear = true;
    for (const auto& off : offsets) clear = clear && KnownFree(tree, p + off);
    if (!clear) continue;
    octomap::point3d floor;
    if (!tree.castRay(p, {0, 0, -1}, floor, /*ignoreUnknownCells=*/false,
                      params.max_height_m + 1.0)) {
      continue;  // unknown below, or no floor within reach
    }
    const double height = p.z() - floor_z;
    if (std::abs(floor.z() - floor_z) > params.floor_tolerance_m || height < params.min_height_m ||
        height > params.max_height_m) {
      continue;
    }
    int enclosing = 0;
    for (int k = 0; k < 8; ++k) {
      const double a = k * M_PI / 4.0;
      octomap::point3d end;
      enclosing += tree.castRay(
          p,
          octomap::point3d(static_cast<float>(std::cos(a)), static_cast<float>(std::sin(a)), 0.0f),
          end, /*ignoreUnknownCells=*/true, 20.0);
    }
    if (enclosing < params.min_enclosing_rays) continue;
    bool spaced = true;
    for (const auto& q : accepted) spaced = spaced && (q - p).norm() >= params.min_spacing_m;
    if (spaced) accepted.push_back(p);
  }
  // Nearest-neighbour order from the first accepted pose.
  std::vector<geometry::Rigid3> route;
  std::vector<bool> used(accepted.size(), false);
  size_t current = 0;
  for (size_t k = 0; k < accepted.size(); ++k) {
    used[current] = true;
    geometry::Rigid3 pose;
    pose.translation = {accepted[current].x(), accepted[current].y(), accepted[current].z()};
    pose.rotation = Eigen::Quaterniond(Eigen::AngleAxisd(yaw(rng), Eigen::Vector3d::UnitZ()));
    route.push_back(pose);
    double best = std::numeric_limits<double>::infinity();
    for (size_t j = 0; j < accepted.size(); ++j) {
      const double dist = (accepted[j] - accepted[current]).norm();
      if (!used[j] && dist < best) {
        best = dist;
        current = j;
      }
    }
  }
  return route;
}

}  // namespace mapd::sim
