#include "client/robot/cloud_planes.h"

#include <pcl/ModelCoefficients.h>
#include <pcl/features/normal_3d.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>
#include <pcl/sample_consensus/method_types.h>
#include <pcl/sample_consensus/model_types.h>
#include <pcl/search/kdtree.h>
#include <pcl/segmentation/region_growing.h>
#include <pcl/segmentation/sac_segmentation.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "geometry/convex_hull2.h"

namespace mapd::robot {
namespace {

Status Bad(const std::string& what) {
  return Status::InvalidArgument("plane extraction params: " + what);
}

// The points of one scan and how they neighbour: an organised cloud's image,
// or (columns == 0) none, and space decides.
struct CloudView {
  const std::vector<Eigen::Vector3f>& points;
  int rows = 0;
  int columns = 0;  // 0: unorganised
  bool wrap_columns = false;
};

float JumpLimit(const PlaneExtractionParams& params, const Eigen::Vector3f& p) {
  return static_cast<float>(params.jump_base_m + params.jump_factor * p.norm());
}

// Components of `mask` connected through image neighbours (same row, next
// column within the jump limit, around the end when the columns wrap; same
// column, next row).
std::vector<std::vector<int>> ImageComponents(const CloudView& cloud, const std::vector<char>& mask,
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
      const float jump = JumpLimit(params, p);
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

// Components of the points `members` (indices into cloud.points): each joined
// to its nearest kSpaceNeighbours within the jump limit of either end. The cap
// keeps a dense cloud linear (all neighbours within 0.3 m of a 1 cm cloud took
// 36 s on the real scan, docs/robot-library.md); chains of near neighbours
// still join a dense surface, and a sparse one joins across the jump limit.
constexpr int kSpaceNeighbours = 32;

std::vector<std::vector<int>> SpaceComponents(const CloudView& cloud,
                                              const std::vector<int>& members,
                                              const PlaneExtractionParams& params) {
  pcl::PointCloud<pcl::PointXYZ>::Ptr xyz(new pcl::PointCloud<pcl::PointXYZ>);
  xyz->reserve(members.size());
  float max_jump = 0.0f;
  for (int i : members) {
    const Eigen::Vector3f& p = cloud.points[static_cast<size_t>(i)];
    xyz->push_back(pcl::PointXYZ(p.x(), p.y(), p.z()));
    max_jump = std::max(max_jump, JumpLimit(params, p));
  }
  pcl::search::KdTree<pcl::PointXYZ> tree;
  tree.setInputCloud(xyz);
  std::vector<char> seen(members.size(), 0);
  std::vector<std::vector<int>> out;
  std::vector<int> stack, found;
  std::vector<float> squared;
  for (size_t start = 0; start < members.size(); ++start) {
    if (seen[start]) continue;
    std::vector<int> comp;
    stack.assign(1, static_cast<int>(start));
    seen[start] = 1;
    while (!stack.empty()) {
      const int k = stack.back();
      stack.pop_back();
      comp.push_back(members[static_cast<size_t>(k)]);
      const Eigen::Vector3f& p = cloud.points[static_cast<size_t>(members[static_cast<size_t>(k)])];
      // Either end's limit joins the pair: search with the largest, keep the
      // pairs within the larger of the two.
      const float own = JumpLimit(params, p);
      tree.radiusSearch(static_cast<int>(k), max_jump, found, squared, kSpaceNeighbours);
      for (size_t f = 0; f < found.size(); ++f) {
        const int j = found[f];
        if (seen[static_cast<size_t>(j)]) continue;
        const float limit = std::max(
            own,
            JumpLimit(params, cloud.points[static_cast<size_t>(members[static_cast<size_t>(j)])]));
        if (squared[f] > limit * limit) continue;
        seen[static_cast<size_t>(j)] = 1;
        stack.push_back(j);
      }
    }
    out.push_back(std::move(comp));
  }
  return out;
}

// Least-squares plane and hull of one component; false if it fails a gate.
bool MakePlane(const CloudView& cloud, const std::vector<int>& comp,
               const PlaneExtractionParams& params, ExtractedPlane* out,
               PlaneExtractionStats* stats) {
  if (comp.size() < params.min_inliers) return false;
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (int i : comp) mean += cloud.points[static_cast<size_t>(i)].cast<double>();
  if (cloud.columns > 0) {
    std::vector<char> rows(static_cast<size_t>(cloud.rows), 0);
    for (int i : comp) rows[static_cast<size_t>(i / cloud.columns)] = 1;
    if (std::count(rows.begin(), rows.end(), 1) < params.min_rows) {
      ++stats->rejected_rows;
      return false;
    }
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

// Region growing over the finite points: k-nearest-neighbour normals, regions
// grown between neighbours whose normals differ by less than the smoothness
// angle, through points flat enough; each region of min_inliers points or
// more through the same gates as a RANSAC component.
std::vector<ExtractedPlane> GrowRegions(const CloudView& cloud, const PlaneExtractionParams& params,
                                        PlaneExtractionStats* stats) {
  std::vector<int> finite;
  pcl::PointCloud<pcl::PointXYZ>::Ptr xyz(new pcl::PointCloud<pcl::PointXYZ>);
  for (size_t i = 0; i < cloud.points.size(); ++i) {
    const Eigen::Vector3f& p = cloud.points[i];
    if (!p.allFinite()) continue;
    finite.push_back(static_cast<int>(i));
    xyz->push_back(pcl::PointXYZ(p.x(), p.y(), p.z()));
  }
  std::vector<ExtractedPlane> planes;
  if (finite.size() < params.min_inliers) return planes;
  pcl::search::KdTree<pcl::PointXYZ>::Ptr tree(new pcl::search::KdTree<pcl::PointXYZ>);
  pcl::PointCloud<pcl::Normal>::Ptr normals(new pcl::PointCloud<pcl::Normal>);
  pcl::NormalEstimation<pcl::PointXYZ, pcl::Normal> estimator;
  estimator.setSearchMethod(tree);
  estimator.setInputCloud(xyz);
  estimator.setKSearch(params.normal_neighbours);
  estimator.compute(*normals);
  pcl::RegionGrowing<pcl::PointXYZ, pcl::Normal> growing;
  growing.setMinClusterSize(static_cast<pcl::uindex_t>(params.min_inliers));
  growing.setMaxClusterSize(std::numeric_limits<pcl::uindex_t>::max());
  growing.setSearchMethod(tree);
  growing.setNumberOfNeighbours(static_cast<unsigned>(params.normal_neighbours));
  growing.setInputCloud(xyz);
  growing.setInputNormals(normals);
  growing.setSmoothnessThreshold(static_cast<float>(params.smoothness_deg * M_PI / 180.0));
  growing.setCurvatureThreshold(static_cast<float>(params.max_curvature));
  std::vector<pcl::PointIndices> regions;
  growing.extract(regions);
  stats->ransac_rounds = 0;
  for (const pcl::PointIndices& region : regions) {
    std::vector<int> comp;
    comp.reserve(region.indices.size());
    for (int k : region.indices) comp.push_back(finite[static_cast<size_t>(k)]);
    ExtractedPlane plane;
    if (MakePlane(cloud, comp, params, &plane, stats)) planes.push_back(std::move(plane));
  }
  return planes;
}

// RANSAC rounds over what is left of `cloud`, each round's inliers split into
// components (image or space) and the good ones kept.
std::vector<ExtractedPlane> Extract(const CloudView& cloud, const PlaneExtractionParams& params,
                                    PlaneExtractionStats* stats) {
  if (params.segmentation == PlaneSegmentation::kRegionGrowing) {
    return GrowRegions(cloud, params, stats);
  }
  const size_t n = cloud.points.size();
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
    std::vector<int> members;
    members.reserve(inliers.indices.size());
    for (int k : inliers.indices) {
      members.push_back(pool[static_cast<size_t>(k)]);
      mask[static_cast<size_t>(members.back())] = 1;
    }
    const auto components = cloud.columns > 0 ? ImageComponents(cloud, mask, params)
                                              : SpaceComponents(cloud, members, params);
    for (const auto& comp : components) {
      ExtractedPlane plane;
      if (MakePlane(cloud, comp, params, &plane, stats)) planes.push_back(std::move(plane));
    }
    pool.erase(std::remove_if(pool.begin(), pool.end(),
                              [&](int i) { return mask[static_cast<size_t>(i)] != 0; }),
               pool.end());
  }
  return planes;
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
  if (segmentation != PlaneSegmentation::kRansac &&
      segmentation != PlaneSegmentation::kRegionGrowing) {
    return Bad("segmentation must be kRansac or kRegionGrowing");
  }
  if (normal_neighbours < 3 || normal_neighbours > 200) {
    return Bad("normal_neighbours must be in [3, 200]");
  }
  if (!(smoothness_deg > 0.0 && smoothness_deg <= 90.0)) {
    return Bad("smoothness_deg must be in (0, 90]");
  }
  if (!(max_curvature > 0.0 && max_curvature <= 1.0)) return Bad("max_curvature must be in (0, 1]");
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
  PlaneExtractionStats local;
  return Extract(CloudView{cloud.points, cloud.rows, cloud.columns, cloud.wrap_columns}, params,
                 stats == nullptr ? &local : stats);
}

StatusOr<std::vector<ExtractedPlane>> ExtractPlanes(const std::vector<Eigen::Vector3f>& points,
                                                    const PlaneExtractionParams& params,
                                                    PlaneExtractionStats* stats) {
  MAPD_RETURN_IF_ERROR(params.Validate());
  PlaneExtractionStats local;
  return Extract(CloudView{points, 1, 0, false}, params, stats == nullptr ? &local : stats);
}

}  // namespace mapd::robot
