#include "sim/plane_extraction.h"

#include <pcl/ModelCoefficients.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>
#include <pcl/sample_consensus/method_types.h>
#include <pcl/sample_consensus/model_types.h>
#include <pcl/segmentation/sac_segmentation.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <map>
#include <string>

#include "geometry/convex_hull2.h"

namespace mapd::sim {
namespace {

Status Bad(const std::string& what) {
  return Status::InvalidArgument("plane extraction params: " + what);
}

// Components of `mask` connected through range-image neighbours (same beam,
// next column with wrap-around, within the jump limit; same column, next beam).
std::vector<std::vector<int>> Components(const LidarScan& scan, const std::vector<char>& mask,
                                         const PlaneExtractionParams& params) {
  std::vector<int> seen(mask.size(), 0);
  std::vector<std::vector<int>> out;
  std::vector<int> stack;
  const int W = scan.columns;
  for (size_t start = 0; start < mask.size(); ++start) {
    if (!mask[start] || seen[start]) continue;
    std::vector<int> comp;
    stack.assign(1, static_cast<int>(start));
    seen[start] = 1;
    while (!stack.empty()) {
      const int i = stack.back();
      stack.pop_back();
      comp.push_back(i);
      const int b = i / W, c = i % W;
      const Eigen::Vector3f& p = scan.points[i];
      const float jump = static_cast<float>(params.jump_base_m + params.jump_factor * p.norm());
      const int neighbours[4][2] = {{b, (c + 1) % W}, {b, (c + W - 1) % W}, {b + 1, c}, {b - 1, c}};
      for (int k = 0; k < 4; ++k) {
        const int nb = neighbours[k][0], nc = neighbours[k][1];
        if (nb < 0 || nb >= scan.beams) continue;
        const int j = nb * W + nc;
        if (!mask[j] || seen[j]) continue;
        if (k < 2 && (scan.points[j] - p).norm() > jump) continue;
        seen[j] = 1;
        stack.push_back(j);
      }
    }
    out.push_back(std::move(comp));
  }
  return out;
}

// Least-squares plane and hull of one component; false if it fails a gate.
bool MakePlane(const LidarScan& scan, const std::vector<int>& comp,
               const PlaneExtractionParams& params, ExtractedPlane* out, ExtractionStats* stats) {
  if (comp.size() < params.min_inliers) return false;
  std::vector<char> beams(scan.beams, 0);
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (int i : comp) {
    mean += scan.points[i].cast<double>();
    beams[i / scan.columns] = 1;
  }
  if (std::count(beams.begin(), beams.end(), 1) < params.min_beams) {
    ++stats->rejected_beams;
    return false;
  }
  mean /= static_cast<double>(comp.size());
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (int i : comp) {
    const Eigen::Vector3d d = scan.points[i].cast<double>() - mean;
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
    const Eigen::Vector3d d = scan.points[i].cast<double>() - mean;
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
  out->inliers = comp.size();
  out->rms_m = rms;
  std::map<int, size_t> votes;
  for (int i : comp) ++votes[scan.labels[i]];
  out->label = std::max_element(votes.begin(), votes.end(), [](const auto& a, const auto& b) {
                 return a.second < b.second;
               })->first;
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
  if (min_beams < 1) return Bad("min_beams must be at least 1");
  if (!(max_rms_m > 0.0)) return Bad("max_rms_m must be > 0");
  if (max_planes < 1) return Bad("max_planes must be at least 1");
  if (!(jump_base_m >= 0.0) || !(jump_factor >= 0.0)) {
    return Bad("jump_base_m and jump_factor must be >= 0");
  }
  return Status::Ok();
}

StatusOr<std::vector<ExtractedPlane>> ExtractPlanes(const LidarScan& scan,
                                                    const PlaneExtractionParams& params,
                                                    ExtractionStats* stats) {
  const size_t n = static_cast<size_t>(scan.beams) * static_cast<size_t>(scan.columns);
  if (scan.beams < 1 || scan.columns < 1 || scan.points.size() != n || scan.labels.size() != n) {
    return Status::InvalidArgument("plane extraction: scan is not beams x columns points");
  }
  ExtractionStats local;
  if (stats == nullptr) stats = &local;
  std::vector<int> pool;  // scan indices not yet taken by a plane
  for (size_t i = 0; i < n; ++i) {
    if (scan.points[i].allFinite()) pool.push_back(static_cast<int>(i));
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
    pcl::PointCloud<pcl::PointXYZ>::Ptr cloud(new pcl::PointCloud<pcl::PointXYZ>);
    cloud->reserve(pool.size());
    for (int i : pool) {
      const Eigen::Vector3f& p = scan.points[i];
      cloud->push_back(pcl::PointXYZ(p.x(), p.y(), p.z()));
    }
    pcl::PointIndices inliers;
    pcl::ModelCoefficients coefficients;
    seg.setInputCloud(cloud);
    seg.segment(inliers, coefficients);
    ++stats->ransac_rounds;
    if (inliers.indices.size() < params.min_inliers) break;
    std::fill(mask.begin(), mask.end(), 0);
    for (int k : inliers.indices) mask[pool[k]] = 1;
    for (const auto& comp : Components(scan, mask, params)) {
      ExtractedPlane plane;
      if (MakePlane(scan, comp, params, &plane, stats)) planes.push_back(std::move(plane));
    }
    pool.erase(std::remove_if(pool.begin(), pool.end(), [&](int i) { return mask[i] != 0; }),
               pool.end());
  }
  return planes;
}

}  // namespace mapd::sim
