#include "fusion/projection.h"

#include <algorithm>
#include <cmath>
#include <string>

namespace mapd::fusion {

using geometry::Rigid3;
using geometry::Vec2;

namespace {

// A ground segment shorter than this has nothing to fuse (projection.h).
constexpr double kMinGroundLengthM = 1e-3;

bool Finite(const Eigen::Vector3d& v) { return v.allFinite(); }

bool FinitePose(const Rigid3& T) {
  return T.rotation.coeffs().allFinite() && T.translation.allFinite();
}

}  // namespace

StatusOr<ProjectedObservation> ProjectToGround(const geometry::SensorObservation& obs,
                                               const geometry::Rigid3& T_map_frame,
                                               FeatureId first_id, const FusionParams& params) {
  if (!FinitePose(T_map_frame)) return Status::InvalidArgument("T_map_frame is not finite");
  if (!FinitePose(obs.T_frame_sensor))
    return Status::InvalidArgument("T_frame_sensor is not finite");
  for (size_t i = 0; i < obs.lines.size(); ++i) {
    if (!Finite(obs.lines[i].a) || !Finite(obs.lines[i].b)) {
      return Status::InvalidArgument("lines[" + std::to_string(i) + "] is not finite");
    }
  }
  for (size_t i = 0; i < obs.planes.size(); ++i) {
    const geometry::PlaneFeature& plane = obs.planes[i];
    bool ok = Finite(plane.normal) && std::isfinite(plane.offset) && plane.normal.norm() > 0.0;
    for (const Eigen::Vector3d& p : plane.boundary) ok = ok && Finite(p);
    if (!ok) return Status::InvalidArgument("planes[" + std::to_string(i) + "] is not finite");
    if (plane.boundary.empty()) {
      return Status::InvalidArgument("planes[" + std::to_string(i) + "] has no boundary points");
    }
  }

  // Normalise the quaternions so that a slightly denormalised pose stays rigid.
  Rigid3 T_map_sensor = T_map_frame * obs.T_frame_sensor;
  T_map_sensor.rotation.normalize();
  const Eigen::Matrix3d R = T_map_sensor.rotation.toRotationMatrix();
  const Eigen::Vector3d& t = T_map_sensor.translation;

  ProjectedObservation out;
  out.sensor_xy_m = t.head<2>();
  FeatureId id = first_id;
  for (const geometry::LineFeature3& line : obs.lines) {
    const FeatureId this_id = id++;  // a skipped feature still consumes its id
    const Eigen::Vector3d a = R * line.a + t;
    const Eigen::Vector3d b = R * line.b + t;
    GroundFeature g;
    g.id = this_id;
    g.segment = {a.head<2>(), b.head<2>()};
    g.z_min_m = std::min(a.z(), b.z());
    g.z_max_m = std::max(a.z(), b.z());
    g.origin = FeatureOrigin::kLine;
    if (g.segment.length() < kMinGroundLengthM) {
      ++out.skipped;
      continue;
    }
    out.ground.push_back(g);
  }

  const double max_vertical_nz = std::sin(params.max_plane_tilt_rad);
  for (const geometry::PlaneFeature& plane : obs.planes) {
    const FeatureId this_id = id++;
    // n' = R n, and from n.x + d = 0 with x = R^T (x' - t): d' = d - n'.t.
    const Eigen::Vector3d n_map = R * plane.normal.normalized();
    const double d_map = plane.offset / plane.normal.norm() - n_map.dot(t);
    std::vector<Eigen::Vector3d> boundary_map;
    boundary_map.reserve(plane.boundary.size());
    for (const Eigen::Vector3d& p : plane.boundary) boundary_map.push_back(R * p + t);

    if (std::abs(n_map.z()) > max_vertical_nz) {
      out.other_planes.push_back({this_id, n_map, d_map, std::move(boundary_map)});
      continue;
    }
    // Ground trace of a vertical plane: n_x x + n_y y + d = 0 with (n_x, n_y)
    // normalised. A plane with n_z = +-1 can only get here if max tilt is 90 deg.
    const double n_xy = n_map.head<2>().norm();
    if (n_xy == 0.0) {
      ++out.skipped;
      continue;
    }
    const Vec2 normal = n_map.head<2>() / n_xy;
    const double offset = d_map / n_xy;
    const Vec2 origin_on_line = -offset * normal;  // closest point of the line to the origin
    const Vec2 direction(-normal.y(), normal.x());
    double t_min = 0.0, t_max = 0.0, z_min = 0.0, z_max = 0.0;
    for (size_t k = 0; k < boundary_map.size(); ++k) {
      const double s = (boundary_map[k].head<2>() - origin_on_line).dot(direction);
      const double z = boundary_map[k].z();
      t_min = k == 0 ? s : std::min(t_min, s);
      t_max = k == 0 ? s : std::max(t_max, s);
      z_min = k == 0 ? z : std::min(z_min, z);
      z_max = k == 0 ? z : std::max(z_max, z);
    }
    if (t_max - t_min < kMinGroundLengthM) {
      ++out.skipped;
      continue;
    }
    GroundFeature g;
    g.id = this_id;
    g.segment = {origin_on_line + t_min * direction, origin_on_line + t_max * direction};
    g.z_min_m = z_min;
    g.z_max_m = z_max;
    g.origin = FeatureOrigin::kPlane;
    out.ground.push_back(g);
  }
  return out;
}

}  // namespace mapd::fusion
