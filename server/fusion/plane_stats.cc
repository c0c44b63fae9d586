// PlaneNode and PlaneStats (plane_engine_impl.h): a raw plane's derived
// fields, and a cluster's moments, hull and fit.
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <iterator>
#include <map>
#include <utility>

#include "fusion/plane_engine_impl.h"
#include "geometry/convex_hull2.h"

namespace mapd::fusion {

void PlaneNode::Prepare() {
  centroid.setZero();
  for (const Eigen::Vector3d& p : boundary) centroid += p;
  centroid /= static_cast<double>(boundary.size());
  radius_m = 0.0;
  ground_min = ground_max = boundary.front().head<2>();
  for (const Eigen::Vector3d& p : boundary) {
    radius_m = std::max(radius_m, (p - centroid).norm());
    ground_min = ground_min.cwiseMin(p.head<2>());
    ground_max = ground_max.cwiseMax(p.head<2>());
  }
}

PlaneStats PlaneStats::OfNode(const PlaneNode& n, RobotId robot, uint32_t support_cap) {
  PlaneStats s;
  s.id = n.id;
  s.member_count = 1;
  s.point_count = n.boundary.size();
  s.mean = n.centroid;
  for (const Eigen::Vector3d& p : n.boundary) s.scatter += (p - s.mean) * (p - s.mean).transpose();
  s.normal_sum = n.normal;
  s.observations.Add(n.observation, support_cap);
  s.robots = {robot};
  s.RebuildHull(n.boundary);
  return s;
}

void PlaneStats::Merge(PlaneStats&& o, uint32_t support_cap) {
  // Chan et al.'s pairwise update of mean and scatter.
  const double na = static_cast<double>(point_count), nb = static_cast<double>(o.point_count);
  const Eigen::Vector3d delta = o.mean - mean;
  const double n = na + nb;
  mean += delta * (nb / n);
  scatter += o.scatter + delta * delta.transpose() * (na * nb / n);
  point_count += o.point_count;
  normal_sum += normal_sum.dot(o.normal_sum) >= 0 ? o.normal_sum : Eigen::Vector3d(-o.normal_sum);
  id = std::min(id, o.id);
  member_count += o.member_count;
  observations.Merge(std::move(o.observations), support_cap);
  std::vector<RobotId> robots_union;
  std::set_union(robots.begin(), robots.end(), o.robots.begin(), o.robots.end(),
                 std::back_inserter(robots_union));
  robots.swap(robots_union);
  std::vector<Eigen::Vector3d> points = std::move(hull);
  points.insert(points.end(), o.hull.begin(), o.hull.end());
  RebuildHull(std::move(points));
}

void PlaneStats::Fit(Eigen::Vector3d* normal, double* offset_m) const {
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(scatter);
  const Eigen::Vector3d& ev = eig.eigenvalues();  // ascending
  Eigen::Vector3d n = eig.eigenvectors().col(0);
  // Collinear or coincident points leave the normal undetermined: the
  // members' own normals then decide.
  if (!(ev(1) > 1e-12 * std::max(ev(2), 1e-300)) || !n.allFinite()) n = normal_sum;
  n.normalize();
  if (n.dot(normal_sum) < 0) n = -n;
  *normal = CanonicalNormal(n);
  *offset_m = -normal->dot(mean);
}

void PlaneStats::RebuildHull(std::vector<Eigen::Vector3d> points) {
  Eigen::Vector3d normal;
  double offset_m;
  Fit(&normal, &offset_m);
  const PlaneBasis basis = PlaneBasis::Of(normal);
  // ConvexHull returns copies of its input points: find each vertex's 3D
  // point by its exact 2D coordinates (the first of equal ones).
  std::map<std::pair<double, double>, size_t> index;
  std::vector<geometry::Vec2> flat;
  flat.reserve(points.size());
  for (size_t i = 0; i < points.size(); ++i) {
    flat.push_back(basis.Project(points[i]));
    index.emplace(std::make_pair(flat.back().x(), flat.back().y()), i);
  }
  hull.clear();
  for (const geometry::Vec2& v : geometry::ConvexHull(std::move(flat))) {
    hull.push_back(points[index.at({v.x(), v.y()})]);
  }
}

FusedPlane PlaneStats::ToFused() const {
  FusedPlane f;
  f.id = id;
  Fit(&f.normal, &f.offset_m);
  const PlaneBasis basis = PlaneBasis::Of(f.normal);
  std::vector<geometry::Vec2> flat;
  f.boundary.reserve(hull.size());
  for (const Eigen::Vector3d& p : hull) {
    f.boundary.push_back(p - f.normal * (f.normal.dot(p) + f.offset_m));
    flat.push_back(basis.Project(f.boundary.back()));
  }
  f.area_m2 = flat.size() >= 3 ? std::abs(PolygonArea(flat)) : 0.0;
  f.z_min_m = f.z_max_m = f.boundary.empty() ? 0.0 : f.boundary.front().z();
  for (const Eigen::Vector3d& p : f.boundary) {
    f.z_min_m = std::min(f.z_min_m, p.z());
    f.z_max_m = std::max(f.z_max_m, p.z());
  }
  f.support = observations.count();
  f.member_count = member_count;
  f.robots = robots;
  return f;
}

}  // namespace mapd::fusion
