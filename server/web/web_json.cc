#include "web/web_json.h"

#include <cmath>

namespace mapd::web {
namespace {

Json Number(double v) { return std::isfinite(v) ? Json(v) : Json(nullptr); }

Json Vec(const Eigen::Vector3d& v) {
  return {{"x", Number(v.x())}, {"y", Number(v.y())}, {"z", Number(v.z())}};
}

Json Pose(const geometry::Rigid3& T) {
  const Eigen::Quaterniond& q = T.rotation;
  return {{"translation", Vec(T.translation)},
          {"rotation", {{"w", q.w()}, {"x", q.x()}, {"y", q.y()}, {"z", q.z()}}}};
}

}  // namespace

Json ToJson(const service::FusedView& v) {
  const fusion::FusedFeature& f = v.feature;
  return {{"id", f.id},
          {"kind", v.kind == service::KindFilter::kPlane ? "plane" : "line"},
          {"a", {{"x", Number(f.segment.a.x())}, {"y", Number(f.segment.a.y())}}},
          {"b", {{"x", Number(f.segment.b.x())}, {"y", Number(f.segment.b.y())}}},
          {"z_min", Number(f.z_min_m)},
          {"z_max", Number(f.z_max_m)},
          {"support", f.support},
          {"member_count", f.member_count},
          {"robots", v.robots}};
}

Json ToJson(const service::PlaneView& v) {
  const fusion::FusedPlane& p = v.plane;
  Json boundary = Json::array();
  for (const Eigen::Vector3d& x : p.boundary) boundary.push_back(Vec(x));
  return {{"id", p.id},
          {"normal", Vec(p.normal)},
          {"offset", Number(p.offset_m)},
          {"boundary", std::move(boundary)},
          {"area", Number(p.area_m2)},
          {"z_min", Number(p.z_min_m)},
          {"z_max", Number(p.z_max_m)},
          {"support", p.support},
          {"member_count", p.member_count},
          {"robots", v.robots}};
}

Json MapJson(uint64_t map_version, const std::vector<service::FusedView>& lines,
             const std::vector<service::PlaneView>& planes) {
  Json features = Json::array(), fused_planes = Json::array();
  for (const service::FusedView& v : lines) features.push_back(ToJson(v));
  for (const service::PlaneView& v : planes) fused_planes.push_back(ToJson(v));
  return {{"map_version", map_version},
          {"features", std::move(features)},
          {"planes", std::move(fused_planes)}};
}

Json ChangeJson(const service::MapChange& c) {
  Json features = Json::array(), fused_planes = Json::array();
  for (const service::FusedView& v : c.lines) features.push_back(ToJson(v));
  for (const service::PlaneView& v : c.planes) fused_planes.push_back(ToJson(v));
  return {{"from_version", c.from_version},    {"map_version", c.to_version},
          {"features", std::move(features)},   {"removed", c.lines_gone},
          {"planes", std::move(fused_planes)}, {"removed_planes", c.planes_gone}};
}

Json ToJson(const storage::MergeRecord& r) {
  Json inputs = Json::array();
  for (const storage::MergeInputRecord& in : r.inputs) {
    Json i = {{"submap_id", in.submap_id}, {"aligned", in.aligned}};
    if (in.aligned) {
      i["t_reference_submap"] = Pose(in.T_reference_submap);
      i["matched_corners"] = in.matched_corners;
      i["residual_m"] = Number(in.residual_m);
      i["overlap_score"] = Number(in.overlap_score);
      // The rest of the placing edge's gate figures (-1: not measured; source
      // empty for the reference and for merges recorded before schema 8).
      i["source"] = in.source;
      i["support_fraction"] = Number(in.support_fraction);
      i["shared_free_ratio"] = Number(in.shared_free_ratio);
      i["restart_spread_voxels"] = Number(in.restart_spread_voxels);
      i["second_residual_m"] = Number(in.second_residual_m);
    }
    inputs.push_back(std::move(i));
  }
  return {{"id", r.id},
          {"state", storage::MergeStateName(r.state)},
          {"created_ns", r.created_ns},
          {"reason", r.reason},
          {"merged_submap_id", r.merged_submap_id},
          {"inputs", std::move(inputs)},
          {"requested_by", r.requested_by},
          {"decided_by", r.decided_by},
          {"decided_ns", r.decided_ns}};
}

std::string Dump(const Json& j) {
  return j.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
}

}  // namespace mapd::web
