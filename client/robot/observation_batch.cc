#include "client/robot/observation_batch.h"

#include <cmath>
#include <string>

namespace mapd::robot {

namespace pb = mapserver::v1;

StatusOr<pb::ObservationBatch> LineBatch(const BatchHeader& header,
                                         const Eigen::Isometry3d& T_frame_sensor,
                                         const std::vector<ExtractedLine>& lines) {
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
