#include "service/proto_convert.h"

namespace mapd::service {

namespace pb = mapserver::v1;

void ToProto(const Eigen::Vector3d& v, pb::Vec3* out) {
  out->set_x(v.x());
  out->set_y(v.y());
  out->set_z(v.z());
}

void ToProto(const geometry::Rigid3& T, pb::Rigid3* out) {
  ToProto(T.translation, out->mutable_translation());
  out->mutable_rotation()->set_w(T.rotation.w());
  out->mutable_rotation()->set_x(T.rotation.x());
  out->mutable_rotation()->set_y(T.rotation.y());
  out->mutable_rotation()->set_z(T.rotation.z());
}

void ToProto(const storage::SubmapMeta& m, pb::SubmapInfo* out) {
  out->set_id(static_cast<uint64_t>(m.id));
  out->set_robot_id(m.robot);
  out->set_name(m.name);
  out->set_format(m.format == storage::SubmapFormat::kOctomapOt ? pb::SUBMAP_FORMAT_OCTOMAP_OT
                                                                : pb::SUBMAP_FORMAT_OCTOMAP_BT);
  out->set_resolution(m.resolution_m);
  out->set_occupied_voxels(m.occupied_voxels);
  out->set_free_voxels(m.free_voxels);
  ToProto(m.bounds_min, out->mutable_bounds_min());
  ToProto(m.bounds_max, out->mutable_bounds_max());
  out->set_size_bytes(m.size_bytes);
  out->set_created_ns(m.created_ns);
}

}  // namespace mapd::service
