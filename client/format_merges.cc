// The stored merges (ListMerges, GetMerge) for people and for other tools.
#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>

#include "client/format.h"
#include "client/text_util.h"
#include "geometry/rigid3.h"

namespace mapd::client {
namespace {

namespace pb = mapserver::v1;

// The weakest evidence over the aligned inputs but the reference: fewest
// corners, largest residual, smallest overlap ("-" when none is aligned).
struct Evidence {
  std::string corners = "-", residual = "-", overlap = "-";
};
Evidence Weakest(const pb::MergeRecord& m) {
  Evidence e;
  bool any = false;
  uint32_t corners = 0;
  double residual = 0, overlap = 0;
  for (int i = 1; i < m.inputs_size(); ++i) {
    const pb::SubmapAlignment& a = m.inputs(i);
    if (!a.has_t_reference_submap()) continue;
    corners = any ? std::min(corners, a.matched_corners()) : a.matched_corners();
    residual = any ? std::max(residual, a.residual_m()) : a.residual_m();
    overlap = any ? std::min(overlap, a.overlap_score()) : a.overlap_score();
    any = true;
  }
  if (any) e = {Printf("%u", corners), Printf("%.3f", residual), Printf("%.2f", overlap)};
  return e;
}

std::string Inputs(const pb::MergeRecord& m) {
  std::string out;
  for (const pb::SubmapAlignment& a : m.inputs()) {
    if (!out.empty()) out += ",";
    out += std::to_string(a.submap_id());
  }
  return out;
}

std::string OrDash(const std::string& s) { return s.empty() ? "-" : Visible(s); }

// The first kShownCorners matched corner pairs of an input (all in --json).
constexpr int kShownCorners = 5;
std::string MatchedCorners(const pb::SubmapAlignment& a) {
  if (a.matched_size() == 0) return "";
  std::string out =
      Printf("    %d matched corner pair%s (in submap -> in reference, m)%s\n", a.matched_size(),
             a.matched_size() == 1 ? "" : "s", a.matched_size() > kShownCorners ? ", first 5" : "");
  for (int i = 0; i < std::min(a.matched_size(), kShownCorners); ++i) {
    const pb::Vec3& s = a.matched(i).in_submap();
    const pb::Vec3& r = a.matched(i).in_reference();
    out += Printf("      (%.3f, %.3f, %.3f) -> (%.3f, %.3f, %.3f)\n", s.x(), s.y(), s.z(), r.x(),
                  r.y(), r.z());
  }
  return out;
}

nlohmann::ordered_json AlignmentJson(const pb::SubmapAlignment& a) {
  nlohmann::ordered_json j;
  j["submap_id"] = a.submap_id();
  j["aligned"] = a.has_t_reference_submap();
  if (!a.has_t_reference_submap()) return j;
  const pb::Rigid3& T = a.t_reference_submap();
  j["t_reference_submap"] = {
      {"translation", {T.translation().x(), T.translation().y(), T.translation().z()}},
      {"rotation_wxyz", {T.rotation().w(), T.rotation().x(), T.rotation().y(), T.rotation().z()}}};
  double yaw = 0, pitch = 0, roll = 0;
  ToRigid3(T).YawPitchRollDeg(&yaw, &pitch, &roll);
  j["yaw_pitch_roll_deg"] = {yaw, pitch, roll};
  j["matched_corners"] = a.matched_corners();
  j["residual_m"] = a.residual_m();
  j["overlap_score"] = a.overlap_score();
  j["source"] = a.source();  // the rest: -1 where not measured (SubmapAlignment)
  j["support_fraction"] = a.support_fraction();
  j["shared_free_ratio"] = a.shared_free_ratio();
  j["restart_spread_voxels"] = a.restart_spread_voxels();
  j["second_residual_m"] = a.second_residual_m();
  j["matched"] = nlohmann::ordered_json::array();
  for (const pb::MatchedCorner& c : a.matched()) {
    j["matched"].push_back(
        {{"in_submap", {c.in_submap().x(), c.in_submap().y(), c.in_submap().z()}},
         {"in_reference", {c.in_reference().x(), c.in_reference().y(), c.in_reference().z()}}});
  }
  return j;
}

nlohmann::ordered_json MergeJson(const pb::MergeRecord& m) {
  nlohmann::ordered_json j;
  j["id"] = m.id();
  j["state"] = MergeStateName(m.state());
  j["inputs"] = nlohmann::ordered_json::array();
  for (const pb::SubmapAlignment& a : m.inputs()) j["inputs"].push_back(AlignmentJson(a));
  j["merged_submap_id"] = m.merged_submap_id();
  j["reason"] = m.reason();
  j["requested_by"] = m.requested_by();
  j["created_ns"] = m.created_ns();
  j["decided_by"] = m.decided_by();
  j["decided_ns"] = m.decided_ns();
  return j;
}

}  // namespace

std::string FormatAlignment(const pb::SubmapAlignment& a) {
  if (!a.has_t_reference_submap()) {
    return Printf("  submap %llu: not aligned\n", static_cast<unsigned long long>(a.submap_id()));
  }
  const geometry::Rigid3 T = ToRigid3(a.t_reference_submap());
  double yaw = 0, pitch = 0, roll = 0;
  T.YawPitchRollDeg(&yaw, &pitch, &roll);
  std::string out = Printf(
      "  submap %llu: xyz (%.3f, %.3f, %.3f) m, yaw/pitch/roll (%.2f, %.2f, %.2f) deg, "
      "%u matched corners, residual %.3f m, overlap %.2f\n",
      static_cast<unsigned long long>(a.submap_id()), T.translation.x(), T.translation.y(),
      T.translation.z(), yaw, pitch, roll, a.matched_corners(), a.residual_m(), a.overlap_score());
  // The rest of the placing edge's evidence, when the server recorded it (the
  // reference input and merges from before it have none).
  if (a.source().empty()) return out;
  const auto figure = [](double v, int digits, const char* unit) {
    return !(v >= 0) || !std::isfinite(v) ? std::string("-") : Printf("%.*f%s", digits, v, unit);
  };
  return out + "    placed by " + a.source() + ": support " + figure(a.support_fraction(), 3, "") +
         ", shared free " + figure(a.shared_free_ratio(), 2, "") + ", restart spread " +
         figure(a.restart_spread_voxels(), 2, " voxels") + ", runner-up residual " +
         figure(a.second_residual_m(), 3, " m") + "\n";
}

geometry::Rigid3 ToRigid3(const pb::Rigid3& T) {
  return geometry::Rigid3::FromQuaternion(
      T.rotation().w(), T.rotation().x(), T.rotation().y(), T.rotation().z(),
      {T.translation().x(), T.translation().y(), T.translation().z()});
}

std::string MergeStateName(pb::MergeState state) {
  switch (state) {
    case pb::MERGE_STATE_PROPOSED:
      return "proposed";
    case pb::MERGE_STATE_ACCEPTED:
      return "accepted";
    case pb::MERGE_STATE_REJECTED:
      return "rejected";
    case pb::MERGE_STATE_REFUSED:
      return "refused";
    default:
      return "unknown";
  }
}

std::string FormatMerges(const pb::ListMergesResponse& merges) {
  std::string out = Printf("%-6s %-9s %-12s %-7s %-7s %-9s %-7s %-12s %-20s %-12s %s\n", "ID",
                           "STATE", "INPUTS", "MERGED", "CORNERS", "RESIDUAL", "OVERLAP",
                           "REQUESTED_BY", "CREATED", "DECIDED_BY", "REASON");
  for (const pb::MergeRecord& m : merges.merges()) {
    const Evidence e = Weakest(m);
    const std::string merged = m.merged_submap_id() ? std::to_string(m.merged_submap_id()) : "-";
    out +=
        Printf("%-6llu %-9s %-12s %-7s %-7s %-9s %-7s %-12s %-20s %-12s %s\n",
               static_cast<unsigned long long>(m.id()), MergeStateName(m.state()).c_str(),
               Inputs(m).c_str(), merged.c_str(), e.corners.c_str(), e.residual.c_str(),
               e.overlap.c_str(), OrDash(m.requested_by()).c_str(), IsoTime(m.created_ns()).c_str(),
               OrDash(m.decided_by()).c_str(), OrDash(m.reason()).c_str());
  }
  out += Printf("%d merge%s\n", merges.merges_size(), merges.merges_size() == 1 ? "" : "s");
  return out;
}

std::string FormatMergesJson(const pb::ListMergesResponse& merges) {
  nlohmann::ordered_json doc;
  doc["merges"] = nlohmann::ordered_json::array();
  for (const pb::MergeRecord& m : merges.merges()) doc["merges"].push_back(MergeJson(m));
  return doc.dump(2, ' ', false, nlohmann::json::error_handler_t::replace) + "\n";
}

std::string FormatMergeRecordJson(const pb::MergeRecord& merge) {
  return MergeJson(merge).dump(2, ' ', false, nlohmann::json::error_handler_t::replace) + "\n";
}

std::string FormatMergeRecord(const pb::MergeRecord& m) {
  std::string out = Printf("merge %llu: %s", static_cast<unsigned long long>(m.id()),
                           MergeStateName(m.state()).c_str());
  if (m.merged_submap_id() != 0)
    out += Printf(", merged submap %llu", static_cast<unsigned long long>(m.merged_submap_id()));
  out += "\n";
  out += Printf("  requested by %s at %s\n", OrDash(m.requested_by()).c_str(),
                IsoTime(m.created_ns()).c_str());
  if (m.decided_ns() != 0) {
    out +=
        Printf("  %s by %s at %s\n", m.state() == pb::MERGE_STATE_REJECTED ? "rejected" : "decided",
               OrDash(m.decided_by()).c_str(), IsoTime(m.decided_ns()).c_str());
  }
  if (!m.reason().empty()) out += "  reason: " + Visible(m.reason()) + "\n";
  for (const pb::SubmapAlignment& a : m.inputs()) out += FormatAlignment(a) + MatchedCorners(a);
  if (m.state() == pb::MERGE_STATE_PROPOSED) {
    out += Printf(
        "  waits for review: mapctl merge approve %llu | mapctl merge reject %llu "
        "--reason ...\n",
        static_cast<unsigned long long>(m.id()), static_cast<unsigned long long>(m.id()));
  }
  return out;
}

}  // namespace mapd::client
