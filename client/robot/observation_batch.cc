#include "client/robot/observation_batch.h"

#include <cmath>
#include <string>

namespace mapd::robot {

namespace pb = mapserver::v1;

StatusOr<pb::ObservationBatch> LineBatch(const BatchHeader& header,
                                         const Eigen::Isometry3d& T_frame_sensor,
                                         const std::vector<ExtractedLine>& lines) {
  return FeatureBatch(header, T_frame_sensor, lines, {});
}

StatusOr<pb::ObservationBatch> FeatureBatch(const BatchHeader& header,
                                            const Eigen::Isometry3d& T_frame_sensor,
                                            const std::vector<ExtractedLine>& lines,
                                            const std::vector<geometry::PlaneFeature>& planes) {
  if (header.robot_id.empty()) return Status::InvalidArgument("robot_id is empty");
  if (header.session_id.empty()) return Status::InvalidArgument("session_id is empty");
  if (header.seq == 0) return Status::InvalidArgument("seq is 0: sequence numbers start at 1");
  if (!T_frame_sensor.matrix().allFinite()) {
    return Status::InvalidArgument("T_frame_sensor is not finite");
  }
  const Eigen::Matrix3d R = T_frame_sensor.linear();
  if (!(R.transpose() * R).isIdentity(1e-6) || !(R.determinant() > 0)) {
    return Status::InvalidArgument(
        "T_frame_sensor's rotation is not a rotation (orthonormal, determinant 1)");
  }
  pb::ObservationBatch batch;
  batch.set_robot_id(header.robot_id);
  batch.set_session_id(header.session_id);
  batch.set_seq(header.seq);
  batch.set_stamp_ns(header.stamp_ns);
  batch.set_session_frame(header.frame);
  pb::Rigid3* pose = batch.mutable_t_frame_sensor();
  const Eigen::Vector3d t = T_frame_sensor.translation();
  const Eigen::Quaterniond q(R);
  pose->mutable_translation()->set_x(t.x());
  pose->mutable_translation()->set_y(t.y());
  pose->mutable_translation()->set_z(t.z());
  pose->mutable_rotation()->set_w(q.w());
  pose->mutable_rotation()->set_x(q.x());
  pose->mutable_rotation()->set_y(q.y());
  pose->mutable_rotation()->set_z(q.z());
  for (std::size_t i = 0; i < lines.size(); ++i) {
    const Segment2& s = lines[i].segment;
    if (!s.a.allFinite() || !s.b.allFinite() || s.a == s.b) {
      return Status::InvalidArgument("lines[" + std::to_string(i) +
                                     "] is not finite or has no length");
    }
    pb::LineSegment* line = batch.add_lines();
    line->mutable_a()->set_x(s.a.x());
    line->mutable_a()->set_y(s.a.y());
    line->mutable_b()->set_x(s.b.x());
    line->mutable_b()->set_y(s.b.y());
  }
  for (std::size_t i = 0; i < planes.size(); ++i) {
    const geometry::PlaneFeature& plane = planes[i];
    const std::string name = "planes[" + std::to_string(i) + "]";
    if (!plane.normal.allFinite() || std::abs(plane.normal.norm() - 1) > 1e-3) {
      return Status::InvalidArgument(name + ".normal is not a unit vector");
    }
    if (!std::isfinite(plane.offset))
      return Status::InvalidArgument(name + ".offset is not finite");
    if (plane.boundary.size() < 3) {
      return Status::InvalidArgument(name + ".boundary has " +
                                     std::to_string(plane.boundary.size()) +
                                     " points, needs 3 or more");
    }
    pb::Plane* out = batch.add_planes();
    out->mutable_normal()->set_x(plane.normal.x());
    out->mutable_normal()->set_y(plane.normal.y());
    out->mutable_normal()->set_z(plane.normal.z());
    out->set_offset(plane.offset);
    for (std::size_t k = 0; k < plane.boundary.size(); ++k) {
      const Eigen::Vector3d& p = plane.boundary[k];
      if (!p.allFinite()) {
        return Status::InvalidArgument(name + ".boundary[" + std::to_string(k) + "] is not finite");
      }
      pb::Vec3* v = out->add_boundary();
      v->set_x(p.x());
      v->set_y(p.y());
      v->set_z(p.z());
    }
  }
  return batch;
}

StatusOr<pb::ObservationBatch> ScanBatch(const BatchHeader& header,
                                         const Eigen::Isometry3d& T_frame_sensor,
                                         const LaserScan& scan,
                                         const LineExtractionParams& params) {
  auto lines = ExtractLines(scan, params);
  if (!lines.ok()) return lines.status();
  return LineBatch(header, T_frame_sensor, *lines);
}

}  // namespace mapd::robot
