#include "voxel/corner_extraction.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <limits>
#include <map>
#include <string>
#include <vector>

#include <Eigen/Dense>
#include <pcl/features/normal_3d.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>
#include <pcl/search/kdtree.h>
#include <pcl/segmentation/extract_clusters.h>
#include <pcl/segmentation/region_growing.h>

#include "voxel/corner_window.h"

namespace mapd::voxel {
namespace {

constexpr double kPi = 3.14159265358979323846;
using Clock = std::chrono::steady_clock;
using Cloud = pcl::PointCloud<pcl::PointXYZ>;

double SecondsSince(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

// A fitted plane n . p + d = 0 (|n| = 1) and the points of its region.
struct Plane {
  Eigen::Vector3d normal;
  double offset = 0.0;
  std::vector<int> points;  // indices into the cloud
  double Distance(const Eigen::Vector3d& p) const { return std::abs(normal.dot(p) + offset); }
  // Distance from the plane to the voxel cube of edge `res` centred at `p`
  // (0 when the plane cuts the voxel).
  double VoxelDistance(const Eigen::Vector3d& p, double res) const {
    return std::max(0.0, Distance(p) - 0.5 * res * normal.cwiseAbs().sum());
  }
};

using PlaneTriple = std::array<int, 3>;  // ascending plane indices

Cloud::Ptr ToCloud(const std::vector<Eigen::Vector3d>& points) {
  Cloud::Ptr cloud(new Cloud);
  cloud->reserve(points.size());
  for (const Eigen::Vector3d& p : points) {
    cloud->push_back(pcl::PointXYZ(static_cast<float>(p.x()), static_cast<float>(p.y()),
                                   static_cast<float>(p.z())));
  }
  return cloud;
}

// B.2: NormalEstimation + RegionGrowing, a least-squares plane per region
// (centroid and smallest principal axis), regions that are not flat dropped.
std::vector<Plane> FitPlanes(const Cloud::Ptr& cloud, const pcl::search::KdTree<pcl::PointXYZ>::Ptr& tree,
                             const std::vector<Eigen::Vector3d>& points, double res,
                             const CornerExtractionParams& params) {
  pcl::PointCloud<pcl::Normal>::Ptr normals(new pcl::PointCloud<pcl::Normal>);
  pcl::NormalEstimation<pcl::PointXYZ, pcl::Normal> estimation;
  estimation.setInputCloud(cloud);
  estimation.setSearchMethod(tree);
  estimation.setRadiusSearch(params.normal_radius * res);
  estimation.compute(*normals);

  pcl::RegionGrowing<pcl::PointXYZ, pcl::Normal> growing;
  growing.setMinClusterSize(params.min_region_size);
  growing.setMaxClusterSize(static_cast<int>(std::min<std::size_t>(cloud->size(), 1u << 30)));
  growing.setSearchMethod(tree);
  growing.setNumberOfNeighbours(params.region_neighbours);
  growing.setInputCloud(cloud);
  growing.setInputNormals(normals);
  growing.setSmoothnessThreshold(static_cast<float>(params.smoothness_deg * kPi / 180.0));
  growing.setCurvatureThreshold(static_cast<float>(params.curvature_threshold));
  std::vector<pcl::PointIndices> regions;
  growing.extract(regions);

  std::vector<Plane> planes;
  for (const pcl::PointIndices& region : regions) {
    const auto n = static_cast<double>(region.indices.size());
    Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
    for (int i : region.indices) centroid += points[static_cast<std::size_t>(i)];
    centroid /= n;
    Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
    for (int i : region.indices) {
      const Eigen::Vector3d d = points[static_cast<std::size_t>(i)] - centroid;
      covariance += d * d.transpose();
    }
    covariance /= n;
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(covariance);
    // eigenvalues ascending: the smallest is the mean squared plane distance.
    const double rms = std::sqrt(std::max(0.0, eigen.eigenvalues()(0)));
    if (rms > params.max_plane_rms * res) continue;
    Plane plane;
    plane.normal = eigen.eigenvectors().col(0).normalized();
    plane.offset = -plane.normal.dot(centroid);
    plane.points = region.indices;
    planes.push_back(std::move(plane));
  }
  return planes;
}

// B.2 for one candidate: among the planes with a point within the search
// radius, take planes by increasing distance, skipping any closer than the
// minimum angle to one already taken; verified when three lie within epsilon.
bool VerifyCandidate(const Eigen::Vector3d& p, double res, const std::vector<Plane>& planes,
                     const std::vector<int>& plane_of_point,
                     const pcl::search::KdTree<pcl::PointXYZ>& tree, double radius,
                     double epsilon, double min_cos_separation, PlaneTriple* triple) {
  std::vector<int> neighbours;
  std::vector<float> sq_distances;
  tree.radiusSearch(pcl::PointXYZ(static_cast<float>(p.x()), static_cast<float>(p.y()),
                                  static_cast<float>(p.z())),
                    radius, neighbours, sq_distances);
  std::vector<int> nearby;
  for (int i : neighbours) {
    const int plane = plane_of_point[static_cast<std::size_t>(i)];
    if (plane >= 0 && std::find(nearby.begin(), nearby.end(), plane) == nearby.end()) {
      nearby.push_back(plane);
    }
  }
  std::sort(nearby.begin(), nearby.end(), [&](int a, int b) {
    return planes[static_cast<std::size_t>(a)].VoxelDistance(p, res) <
           planes[static_cast<std::size_t>(b)].VoxelDistance(p, res);
  });
  int taken = 0;
  for (int plane : nearby) {
    const Plane& candidate = planes[static_cast<std::size_t>(plane)];
    if (candidate.VoxelDistance(p, res) > epsilon) break;
    bool separated = true;
    for (int t = 0; t < taken; ++t) {
      const Plane& other = planes[static_cast<std::size_t>((*triple)[static_cast<std::size_t>(t)])];
      if (std::abs(candidate.normal.dot(other.normal)) > min_cos_separation) separated = false;
    }
    if (!separated) continue;
    (*triple)[static_cast<std::size_t>(taken++)] = plane;
    if (taken == 3) {
      std::sort(triple->begin(), triple->end());
      return true;
    }
  }
  return false;
}

// Orients `normal` (of a face through `face_point`) towards free space as seen
// in the grid; when the grid knows no free space there, away from the corner's
// other faces (`other_faces`: a point on them near the corner).
Eigen::Vector3d OrientNormal(const VoxelGrid& grid, const Eigen::Vector3d& normal,
                             const Eigen::Vector3d& face_point,
                             const Eigen::Vector3d& other_faces) {
  int vote = 0;  // > 0: free space on the +normal side
  for (int step = 1; step <= 3; ++step) {
    const Eigen::Vector3d offset = normal * (step * grid.resolution());
    vote += grid.State(grid.PointToKey(face_point + offset)) == VoxelState::kFree;
    vote -= grid.State(grid.PointToKey(face_point - offset)) == VoxelState::kFree;
  }
  if (vote == 0) vote = normal.dot(other_faces - face_point) < 0.0 ? 1 : -1;
  return vote > 0 ? normal : Eigen::Vector3d(-normal);
}

// B.3 for one cluster: the intersection of its most voted plane triple.
bool MakeCorner(const VoxelGrid& grid, const std::vector<Plane>& planes,
                const std::vector<Eigen::Vector3d>& points, const std::vector<int>& members,
                const std::vector<Eigen::Vector3d>& positions,
                const std::vector<PlaneTriple>& triples, double max_offset, Corner* corner,
                PlaneTriple* corner_planes) {
  std::map<PlaneTriple, int> votes;
  for (int m : members) ++votes[triples[static_cast<std::size_t>(m)]];
  const PlaneTriple triple =
      std::max_element(votes.begin(), votes.end(),
                       [](const auto& a, const auto& b) { return a.second < b.second; })
          ->first;
  Eigen::Matrix3d n;
  Eigen::Vector3d d;
  for (int k = 0; k < 3; ++k) {
    const Plane& plane = planes[static_cast<std::size_t>(triple[static_cast<std::size_t>(k)])];
    n.row(k) = plane.normal.transpose();
    d(k) = -plane.offset;
  }
  // Three normals pairwise >= 30 deg apart can still be nearly coplanar.
  if (std::abs(n.determinant()) < 0.1) return false;
  const Eigen::Vector3d position = n.colPivHouseholderQr().solve(d);
  double nearest = std::numeric_limits<double>::infinity();
  for (int m : members) {
    nearest = std::min(nearest, (positions[static_cast<std::size_t>(m)] - position).norm());
  }
  if (nearest > max_offset) return false;

  // A point of each face near the corner, for orienting the normals.
  std::array<Eigen::Vector3d, 3> face_points;
  const double near = 4.0 * grid.resolution();
  for (int k = 0; k < 3; ++k) {
    const Plane& plane = planes[static_cast<std::size_t>(triple[static_cast<std::size_t>(k)])];
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    int count = 0;
    for (int i : plane.points) {
      const Eigen::Vector3d& p = points[static_cast<std::size_t>(i)];
      if ((p - position).norm() <= near) {
        sum += p;
        ++count;
      }
    }
    face_points[static_cast<std::size_t>(k)] = count > 0 ? Eigen::Vector3d(sum / count) : position;
  }
  corner->position = position;
  for (std::size_t k = 0; k < 3; ++k) {
    const Eigen::Vector3d others = 0.5 * (face_points[(k + 1) % 3] + face_points[(k + 2) % 3]);
    corner->normals[k] = OrientNormal(grid, n.row(static_cast<Eigen::Index>(k)).transpose(),
                                      face_points[k], others);
  }
  corner->support = static_cast<int>(members.size());
  *corner_planes = triple;
  return true;
}

}  // namespace

Status CornerExtractionParams::Validate() const {
  auto positive = [](double v) { return std::isfinite(v) && v > 0.0; };
  if (window_size < 3 || window_size > 31 || window_size % 2 == 0) {
    return Status::InvalidArgument("window_size must be odd and in [3, 31]");
  }
  if (tau_change < 1) return Status::InvalidArgument("tau_change must be >= 1");
  if (!positive(plane_epsilon)) return Status::InvalidArgument("plane_epsilon must be > 0");
  if (!(min_plane_angle_deg >= 0.0 && min_plane_angle_deg < 90.0)) {
    return Status::InvalidArgument("min_plane_angle_deg must be in [0, 90)");
  }
  if (!positive(plane_search_radius)) {
    return Status::InvalidArgument("plane_search_radius must be > 0");
  }
  if (!positive(normal_radius)) return Status::InvalidArgument("normal_radius must be > 0");
  if (region_neighbours < 3) return Status::InvalidArgument("region_neighbours must be >= 3");
  if (!(smoothness_deg > 0.0 && smoothness_deg < 90.0)) {
    return Status::InvalidArgument("smoothness_deg must be in (0, 90)");
  }
  if (!positive(curvature_threshold)) {
    return Status::InvalidArgument("curvature_threshold must be > 0");
  }
  if (min_region_size < 3) return Status::InvalidArgument("min_region_size must be >= 3");
  if (!positive(max_plane_rms)) return Status::InvalidArgument("max_plane_rms must be > 0");
  if (!positive(cluster_radius)) return Status::InvalidArgument("cluster_radius must be > 0");
  if (!positive(max_corner_offset)) {
    return Status::InvalidArgument("max_corner_offset must be > 0");
  }
  if (max_table_bytes == 0) return Status::InvalidArgument("max_table_bytes must be > 0");
  return Status::Ok();
}

StatusOr<CornerExtractionResult> ExtractCorners(const VoxelGrid& grid,
                                                const CornerExtractionParams& params) {
  MAPD_RETURN_IF_ERROR(params.Validate());
  CornerExtractionResult result;
  result.occupied_voxels = grid.num_occupied();
  if (grid.num_occupied() > params.max_occupied_voxels) {
    return Status::ResourceExhausted("map has " + std::to_string(grid.num_occupied()) +
                                     " occupied voxels; the limit is " +
                                     std::to_string(params.max_occupied_voxels));
  }
  const double res = grid.resolution();

  // B.1: candidates by the sliding window.
  auto start = Clock::now();
  StatusOr<internal::WindowCandidates> window = internal::FindWindowCandidates(
      grid, params.window_size, params.tau_change, params.max_table_bytes);
  if (!window.ok()) return window.status();
  result.candidates = window->keys.size();
  result.table_blocks = window->blocks;
  result.seconds_window = SecondsSince(start);
  if (window->keys.empty()) return result;

  // B.2: planes of the whole map, then the candidates' three planes.
  start = Clock::now();
  const std::vector<Eigen::Vector3d>& points = grid.occupied_centres();
  const Cloud::Ptr cloud = ToCloud(points);
  pcl::search::KdTree<pcl::PointXYZ>::Ptr tree(new pcl::search::KdTree<pcl::PointXYZ>);
  tree->setInputCloud(cloud);
  const std::vector<Plane> planes = FitPlanes(cloud, tree, points, res, params);
  result.planes = planes.size();
  std::vector<int> plane_of_point(points.size(), -1);
  for (std::size_t p = 0; p < planes.size(); ++p) {
    for (int i : planes[p].points) plane_of_point[static_cast<std::size_t>(i)] = static_cast<int>(p);
  }
  result.seconds_planes = SecondsSince(start);

  start = Clock::now();
  const double min_cos = std::cos(params.min_plane_angle_deg * kPi / 180.0);
  std::vector<Eigen::Vector3d> kept;
  std::vector<PlaneTriple> triples;
  for (const VoxelKey& key : window->keys) {
    const Eigen::Vector3d p = grid.KeyToCentre(key);
    PlaneTriple triple{};
    if (VerifyCandidate(p, res, planes, plane_of_point, *tree, params.plane_search_radius * res,
                        params.plane_epsilon * res, min_cos, &triple)) {
      kept.push_back(p);
      triples.push_back(triple);
    }
  }
  result.verified_candidates = kept.size();
  result.seconds_verify = SecondsSince(start);
  if (kept.empty()) return result;

  // B.3: clusters of verified candidates, one corner each.
  start = Clock::now();
  const Cloud::Ptr kept_cloud = ToCloud(kept);
  pcl::search::KdTree<pcl::PointXYZ>::Ptr kept_tree(new pcl::search::KdTree<pcl::PointXYZ>);
  kept_tree->setInputCloud(kept_cloud);
  pcl::EuclideanClusterExtraction<pcl::PointXYZ> clustering;
  clustering.setClusterTolerance(params.cluster_radius * res);
  clustering.setMinClusterSize(1);
  clustering.setMaxClusterSize(static_cast<int>(kept.size()));
  clustering.setSearchMethod(kept_tree);
  clustering.setInputCloud(kept_cloud);
  std::vector<pcl::PointIndices> clusters;
  clustering.extract(clusters);
  result.clusters = clusters.size();
  // Clusters whose planes are the same three meet at the same point: one corner.
  std::map<PlaneTriple, std::size_t> corner_of_planes;
  for (const pcl::PointIndices& cluster : clusters) {
    Corner corner;
    PlaneTriple corner_planes{};
    if (!MakeCorner(grid, planes, points, cluster.indices, kept, triples,
                    params.max_corner_offset * res, &corner, &corner_planes)) {
      continue;
    }
    const auto [it, inserted] = corner_of_planes.emplace(corner_planes, result.corners.size());
    if (inserted) {
      result.corners.push_back(corner);
    } else {
      result.corners[it->second].support += corner.support;
    }
  }
  result.seconds_cluster = SecondsSince(start);
  return result;
}

}  // namespace mapd::voxel
