#include "service/ingest_batch.h"

#include <cmath>
#include <cstdio>
#include <sstream>

#include "common/text_escape.h"

namespace mapd::service {
namespace {

namespace pb = mapserver::v1;

Status CheckScalar(double v, const std::string& field, double max_abs) {
  if (std::isnan(v)) return Status::InvalidArgument(field + " is NaN");
  if (std::isinf(v)) return Status::InvalidArgument(field + " is infinite");
  if (std::abs(v) > max_abs) {
    std::ostringstream m;
    m << field << " = " << v << " m is beyond the limit of " << max_abs
      << " m (a unit or frame error?)";
    return Status::InvalidArgument(m.str());
  }
  return Status::Ok();
}

Status ConvertVec(const pb::Vec3& v, const std::string& field, double max_abs,
                  Eigen::Vector3d* out) {
  MAPD_RETURN_IF_ERROR(CheckScalar(v.x(), field + ".x", max_abs));
  MAPD_RETURN_IF_ERROR(CheckScalar(v.y(), field + ".y", max_abs));
  MAPD_RETURN_IF_ERROR(CheckScalar(v.z(), field + ".z", max_abs));
  *out = {v.x(), v.y(), v.z()};
  return Status::Ok();
}

// A unit vector (quaternion or normal) within `tol`; normalised on the way.
Status CheckUnitNorm(double norm, const std::string& field, double tol) {
  if (std::abs(norm - 1.0) > tol) {
    std::ostringstream m;
    m << field << " has norm " << norm << "; a unit "
      << (field.find("rotation") != std::string::npos ? "quaternion" : "vector")
      << " is required (|norm - 1| <= " << tol << ")";
    return Status::InvalidArgument(m.str());
  }
  return Status::Ok();
}

}  // namespace

std::string Metres(double v) {
  char text[32];
  std::snprintf(text, sizeof(text), "%.6g m", v);
  return text;
}

bool ValidId(const std::string& id, uint32_t max_length) {
  if (id.empty() || id.size() > max_length) return false;
  for (char c : id) {
    const bool ok = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') ||
                    c == '_' || c == '-' || c == '.';
    if (!ok) return false;
  }
  return true;
}

StatusOr<IngestBatch> ValidateBatch(const pb::ObservationBatch& in, const IngestLimits& limits) {
  IngestBatch out;
  if (!ValidId(in.robot_id(), limits.max_id_length)) {
    return Status::InvalidArgument("robot_id '" + EscapeControlChars(in.robot_id().substr(0, 64)) +
                                   "' must be 1-" + std::to_string(limits.max_id_length) +
                                   " characters of [A-Za-z0-9_.-]");
  }
  if (!ValidId(in.session_id(), limits.max_id_length)) {
    return Status::InvalidArgument(
        "session_id '" + EscapeControlChars(in.session_id().substr(0, 64)) + "' must be 1-" +
        std::to_string(limits.max_id_length) + " characters of [A-Za-z0-9_.-]");
  }
  if (in.seq() == 0) return Status::InvalidArgument("seq is 0; sequence numbers start at 1");
  if (in.seq() > static_cast<uint64_t>(INT64_MAX)) {
    return Status::InvalidArgument("seq is larger than 2^63 - 1");
  }
  const size_t n_features =
      static_cast<size_t>(in.lines_size()) + static_cast<size_t>(in.planes_size());
  if (n_features > limits.max_features_per_batch) {
    return Status::ResourceExhausted(
        "batch has " + std::to_string(n_features) + " features (lines + planes); the limit is " +
        std::to_string(limits.max_features_per_batch) + " (max_features_per_batch): split it");
  }
  if (!in.has_t_frame_sensor() || !in.t_frame_sensor().has_rotation() ||
      !in.t_frame_sensor().has_translation()) {
    return Status::InvalidArgument("T_frame_sensor (translation and rotation) is required");
  }
  switch (in.session_frame()) {
    case pb::SESSION_FRAME_UNSPECIFIED:
    case pb::SESSION_FRAME_MAP:
      out.frame_kind = storage::FrameKind::kMap;
      break;
    case pb::SESSION_FRAME_LOCAL:
      out.frame_kind = storage::FrameKind::kLocal;
      break;
    default:
      return Status::InvalidArgument("session_frame has unknown value " +
                                     std::to_string(in.session_frame()));
  }
  const double max_abs = limits.max_abs_coordinate_m;
  geometry::SensorObservation& f = out.features;
  MAPD_RETURN_IF_ERROR(ConvertVec(in.t_frame_sensor().translation(), "T_frame_sensor.translation",
                                  max_abs, &f.T_frame_sensor.translation));
  const pb::Quaternion& q = in.t_frame_sensor().rotation();
  for (const auto& [v, name] : {std::pair{q.w(), "w"}, {q.x(), "x"}, {q.y(), "y"}, {q.z(), "z"}}) {
    MAPD_RETURN_IF_ERROR(CheckScalar(v, std::string("T_frame_sensor.rotation.") + name, 2.0));
  }
  Eigen::Quaterniond rotation(q.w(), q.x(), q.y(), q.z());
  MAPD_RETURN_IF_ERROR(
      CheckUnitNorm(rotation.norm(), "T_frame_sensor.rotation", limits.quaternion_tolerance));
  f.T_frame_sensor.rotation = rotation.normalized();

  f.lines.resize(static_cast<size_t>(in.lines_size()));
  for (int i = 0; i < in.lines_size(); ++i) {
    const std::string field = "lines[" + std::to_string(i) + "]";
    geometry::LineFeature3& l = f.lines[static_cast<size_t>(i)];
    MAPD_RETURN_IF_ERROR(ConvertVec(in.lines(i).a(), field + ".a", max_abs, &l.a));
    MAPD_RETURN_IF_ERROR(ConvertVec(in.lines(i).b(), field + ".b", max_abs, &l.b));
    const double length_m = (l.a - l.b).norm();
    if (length_m < 1e-9) {
      return Status::InvalidArgument(field + " has zero length (a == b)");
    }
    if (length_m > limits.max_feature_length_m) {
      return Status::InvalidArgument(field + " is " + Metres(length_m) + " long; the limit is " +
                                     Metres(limits.max_feature_length_m) +
                                     " (limits.max_feature_length_m): no wall is that long");
    }
  }
  f.planes.resize(static_cast<size_t>(in.planes_size()));
  for (int i = 0; i < in.planes_size(); ++i) {
    const std::string field = "planes[" + std::to_string(i) + "]";
    const pb::Plane& p = in.planes(i);
    geometry::PlaneFeature& out_p = f.planes[static_cast<size_t>(i)];
    MAPD_RETURN_IF_ERROR(ConvertVec(p.normal(), field + ".normal", 2.0, &out_p.normal));
    MAPD_RETURN_IF_ERROR(
        CheckUnitNorm(out_p.normal.norm(), field + ".normal", limits.quaternion_tolerance));
    out_p.normal.normalize();
    MAPD_RETURN_IF_ERROR(CheckScalar(p.offset(), field + ".offset", max_abs));
    out_p.offset = p.offset();
    if (p.boundary_size() < 3) {
      return Status::InvalidArgument(field + ".boundary has " + std::to_string(p.boundary_size()) +
                                     " points; a plane needs at least 3");
    }
    if (static_cast<uint32_t>(p.boundary_size()) > limits.max_boundary_points) {
      return Status::ResourceExhausted(
          field + ".boundary has " + std::to_string(p.boundary_size()) + " points; the limit is " +
          std::to_string(limits.max_boundary_points) +
          " (max_boundary_points): send its convex hull");
    }
    out_p.boundary.resize(static_cast<size_t>(p.boundary_size()));
    Eigen::Vector3d lo = Eigen::Vector3d::Constant(HUGE_VAL), hi = -lo;
    for (int k = 0; k < p.boundary_size(); ++k) {
      Eigen::Vector3d& corner = out_p.boundary[static_cast<size_t>(k)];
      MAPD_RETURN_IF_ERROR(ConvertVec(p.boundary(k), field + ".boundary[" + std::to_string(k) + "]",
                                      max_abs, &corner));
      lo = lo.cwiseMin(corner);
      hi = hi.cwiseMax(corner);
    }
    if (const double span_m = (hi - lo).norm(); span_m > limits.max_feature_length_m) {
      return Status::InvalidArgument(field + ".boundary spans " + Metres(span_m) +
                                     "; the limit is " + Metres(limits.max_feature_length_m) +
                                     " (limits.max_feature_length_m)");
    }
  }
  out.robot = in.robot_id();
  out.session = in.session_id();
  out.seq = in.seq();
  out.stamp_ns = in.stamp_ns();
  return out;
}

}  // namespace mapd::service
