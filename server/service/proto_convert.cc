#include "service/proto_convert.h"

#include <cmath>
#include <string>

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
  out->set_merged(m.robot == storage::kMergedRobot);
}

void ToProto(const FusedView& v, pb::FusedFeature* out) {
  const fusion::FusedFeature& f = v.feature;
  out->set_id(f.id);
  out->set_kind(v.kind == KindFilter::kPlane ? pb::FEATURE_KIND_PLANE : pb::FEATURE_KIND_LINE);
  out->mutable_a()->set_x(f.segment.a.x());
  out->mutable_a()->set_y(f.segment.a.y());
  out->mutable_b()->set_x(f.segment.b.x());
  out->mutable_b()->set_y(f.segment.b.y());
  out->set_z_min(f.z_min_m);
  out->set_z_max(f.z_max_m);
  out->set_support(f.support);
  out->set_member_count(f.member_count);
  for (const std::string& r : v.robots) out->add_robots(r);
}

void ToProto(const PlaneView& v, pb::FusedPlane* out) {
  const fusion::FusedPlane& p = v.plane;
  out->set_id(p.id);
  ToProto(p.normal, out->mutable_normal());
  out->set_offset(p.offset_m);
  for (const Eigen::Vector3d& x : p.boundary) ToProto(x, out->add_boundary());
  out->set_area(p.area_m2);
  out->set_z_min(p.z_min_m);
  out->set_z_max(p.z_max_m);
  out->set_support(p.support);
  out->set_member_count(p.member_count);
  for (const std::string& r : v.robots) out->add_robots(r);
}

Status FromProto(const pb::BoundingBox2& in, geometry::Box2* out) {
  for (double v : {in.min().x(), in.min().y(), in.max().x(), in.max().y()}) {
    if (!std::isfinite(v)) return Status::InvalidArgument("bbox has a non-finite coordinate");
  }
  if (in.min().x() > in.max().x() || in.min().y() > in.max().y()) {
    return Status::InvalidArgument("bbox.min must not exceed bbox.max on either axis");
  }
  *out = geometry::Box2{{in.min().x(), in.min().y()}, {in.max().x(), in.max().y()}};
  return Status::Ok();
}

Status FromProto(pb::FeatureKind in, KindFilter* out) {
  switch (in) {
    case pb::FEATURE_KIND_UNSPECIFIED:
      *out = KindFilter::kAny;
      return Status::Ok();
    case pb::FEATURE_KIND_LINE:
      *out = KindFilter::kLine;
      return Status::Ok();
    case pb::FEATURE_KIND_PLANE:
      *out = KindFilter::kPlane;
      return Status::Ok();
    default:
      return Status::InvalidArgument("kind has unknown value " + std::to_string(in));
  }
}

}  // namespace mapd::service
