#include "client/robot/cloud_planes.h"

#include <pcl/ModelCoefficients.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>
#include <pcl/sample_consensus/method_types.h>
#include <pcl/sample_consensus/model_types.h>
#include <pcl/segmentation/sac_segmentation.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <string>

#include "geometry/convex_hull2.h"

namespace mapd::robot {
namespace {

Status Bad(const std::string& what) {
  return Status::InvalidArgument("plane extraction params: " + what);
}

// Components of `mask` connected through image neighbours (same row, next
// column within the jump limit, around the end when the columns wrap; same
// column, next row).
std::vector<std::vector<int>> Components(const OrganisedCloud& cloud, const std::vector<char>& mask,
                                         const PlaneExtractionParams& params) {
  std::vector<int> seen(mask.size(), 0);
  std::vector<std::vector<int>> out;
  std::vector<int> stack;
  const int W = cloud.columns;
  for (size_t start = 0; start < mask.size(); ++start) {
    if (!mask[start] || seen[start]) continue;
    std::vector<int> comp;
    stack.assign(1, static_cast<int>(start));
    seen[start] = 1;
    while (!stack.empty()) {
      const int i = stack.back();
      stack.pop_back();
      comp.push_back(i);
      const int r = i / W, c = i % W;
      const Eigen::Vector3f& p = cloud.points[static_cast<size_t>(i)];
      const float jump = static_cast<float>(params.jump_base_m + params.jump_factor * p.norm());
      const int neighbours[4][2] = {{r, c + 1}, {r, c - 1}, {r + 1, c}, {r - 1, c}};
      for (int k = 0; k < 4; ++k) {
        const int nr = neighbours[k][0];
        int nc = neighbours[k][1];
        if (nr < 0 || nr >= cloud.rows) continue;
        if (nc < 0 || nc >= W) {
          if (!cloud.wrap_columns) continue;
          nc = (nc + W) % W;
        }
        const int j = nr * W + nc;
        if (!mask[static_cast<size_t>(j)] || seen[static_cast<size_t>(j)]) continue;
        if (k < 2 && (cloud.points[static_cast<size_t>(j)] - p).norm() > jump) continue;
        seen[static_cast<size_t>(j)] = 1;
        stack.push_back(j);
      }
    }
    out.push_back(std::move(comp));
  }
  return out;
}

// Least-squares plane and hull of one component; false if it fails a gate.
bool MakePlane(const OrganisedCloud& cloud, const std::vector<int>& comp,
               const PlaneExtractionParams& params, ExtractedPlane* out,
               PlaneExtractionStats* stats) {
  if (comp.size() < params.min_inliers) return false;
  std::vector<char> rows(static_cast<size_t>(cloud.rows), 0);
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (int i : comp) {
    mean += cloud.points[static_cast<size_t>(i)].cast<double>();
    rows[static_cast<size_t>(i / cloud.columns)] = 1;
  }
  if (std::count(rows.begin(), rows.end(), 1) < params.min_rows) {
    ++stats->rejected_rows;
    return false;
  }
  mean /= static_cast<double>(comp.size());
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (int i : comp) {
    const Eigen::Vector3d d = cloud.points[static_cast<size_t>(i)].cast<double>() - mean;
    cov += d * d.transpose();
  }
  cov /= static_cast<double>(comp.size());
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(cov);  // ascending eigenvalues
  const double rms = std::sqrt(std::max(0.0, eig.eigenvalues()(0)));
  if (rms > params.max_rms_m) {
    ++stats->rejected_rough;
    return false;
  }
  Eigen::Vector3d n = eig.eigenvectors().col(0);
  if (n.dot(mean) > 0) n = -n;                          // towards the sensor at the origin
  const Eigen::Vector3d u = eig.eigenvectors().col(2);  // longest in-plane direction
  const Eigen::Vector3d v = n.cross(u);
  std::vector<geometry::Vec2> in_plane;
  in_plane.reserve(comp.size());
  for (int i : comp) {
    const Eigen::Vector3d d = cloud.points[static_cast<size_t>(i)].cast<double>() - mean;
    in_plane.emplace_back(d.dot(u), d.dot(v));
  }
  const std::vector<geometry::Vec2> hull = geometry::ConvexHull(std::move(in_plane));
  if (hull.size() < 3) return false;
  geometry::Vec2 lo = hull.front(), hi = hull.front();
  for (const auto& h : hull) {
    lo = lo.cwiseMin(h);
    hi = hi.cwiseMax(h);
  }
  const geometry::Vec2 size = hi - lo;
  if (std::max(size.x(), size.y()) < params.min_extent_m ||
      std::min(size.x(), size.y()) < params.min_width_m) {
    ++stats->rejected_small;
    return false;
  }
  out->feature.normal = n;
  out->feature.offset = -n.dot(mean);
  out->feature.boundary.clear();
  for (const auto& h : hull) out->feature.boundary.push_back(mean + h.x() * u + h.y() * v);
  out->indices = comp;
  out->rms_m = rms;
  return true;
}

}  // namespace

Status PlaneExtractionParams::Validate() const {
  if (!(distance_m > 0.0 && distance_m <= 1.0)) return Bad("distance_m must be in (0, 1]");
  if (max_iterations < 1) return Bad("max_iterations must be at least 1");
  if (min_inliers < 3) return Bad("min_inliers must be at least 3");
  if (!(min_extent_m >= 0.0) || !(min_width_m >= 0.0)) {
    return Bad("min_extent_m and min_width_m must be >= 0");
  }
  if (min_rows < 1) return Bad("min_rows must be at least 1");
  if (!(max_rms_m > 0.0)) return Bad("max_rms_m must be > 0");
  if (max_planes < 1) return Bad("max_planes must be at least 1");
  if (!(jump_base_m >= 0.0) || !(jump_factor >= 0.0)) {
    return Bad("jump_base_m and jump_factor must be >= 0");
  }
  return Status::Ok();
}

StatusOr<std::vector<ExtractedPlane>> ExtractPlanes(const OrganisedCloud& cloud,
                                                    const PlaneExtractionParams& params,
                                                    PlaneExtractionStats* stats) {
  MAPD_RETURN_IF_ERROR(params.Validate());
  if (cloud.rows < 1 || cloud.columns < 1 ||
      cloud.points.size() != static_cast<size_t>(cloud.rows) * static_cast<size_t>(cloud.columns)) {
    return Status::InvalidArgument("plane extraction: the cloud is not rows x columns points (" +
                                   std::to_string(cloud.rows) + " x " +
                                   std::to_string(cloud.columns) + ", " +
                                   std::to_string(cloud.points.size()) + " points)");
  }
  const size_t n = cloud.points.size();
  PlaneExtractionStats local;
  if (stats == nullptr) stats = &local;
  std::vector<int> pool;  // indices not yet taken by a plane
  for (size_t i = 0; i < n; ++i) {
    if (cloud.points[i].allFinite()) pool.push_back(static_cast<int>(i));
  }
  pcl::SACSegmentation<pcl::PointXYZ> seg;
  seg.setModelType(pcl::SACMODEL_PLANE);
  seg.setMethodType(pcl::SAC_RANSAC);
  seg.setDistanceThreshold(params.distance_m);
  seg.setMaxIterations(params.max_iterations);
  seg.setOptimizeCoefficients(true);
  std::vector<ExtractedPlane> planes;
  std::vector<char> mask(n, 0);
  for (int round = 0; round < params.max_planes && pool.size() >= params.min_inliers; ++round) {
    pcl::PointCloud<pcl::PointXYZ>::Ptr points(new pcl::PointCloud<pcl::PointXYZ>);
    points->reserve(pool.size());
    for (int i : pool) {
      const Eigen::Vector3f& p = cloud.points[static_cast<size_t>(i)];
      points->push_back(pcl::PointXYZ(p.x(), p.y(), p.z()));
    }
    pcl::PointIndices inliers;
    pcl::ModelCoefficients coefficients;
    seg.setInputCloud(points);
    seg.segment(inliers, coefficients);
    ++stats->ransac_rounds;
    if (inliers.indices.size() < params.min_inliers) break;
    std::fill(mask.begin(), mask.end(), 0);
    for (int k : inliers.indices) mask[static_cast<size_t>(pool[static_cast<size_t>(k)])] = 1;
    for (const auto& comp : Components(cloud, mask, params)) {
      ExtractedPlane plane;
      if (MakePlane(cloud, comp, params, &plane, stats)) planes.push_back(std::move(plane));
    }
    pool.erase(std::remove_if(pool.begin(), pool.end(),
                              [&](int i) { return mask[static_cast<size_t>(i)] != 0; }),
               pool.end());
  }
  return planes;
}

}  // namespace mapd::robot
