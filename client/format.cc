#include "client/format.h"

#include <google/protobuf/util/json_util.h>

#include <cmath>
#include <cstdio>
#include <ctime>
#include <nlohmann/json.hpp>

#include "client/text_util.h"

namespace mapd::client {
namespace {

namespace pb = mapserver::v1;

// A finite number rounded to 4 decimals (0.1 mm), null otherwise: GeoJSON has
// no NaN or infinity, and more digits only add bytes.
nlohmann::ordered_json JsonNumber(double v) {
  if (!std::isfinite(v)) return nullptr;
  const double rounded = std::round(v * 1e4) / 1e4;
  return rounded == 0 ? 0.0 : rounded;  // no "-0.0"
}

std::string Join(const google::protobuf::RepeatedPtrField<std::string>& items, const char* sep) {
  std::string out;
  for (const std::string& s : items) {
    if (!out.empty()) out += sep;
    out += s;
  }
  return out;
}

std::string HumanBytes(uint64_t bytes) {
  const char* units[] = {"B", "KiB", "MiB", "GiB", "TiB"};
  double v = static_cast<double>(bytes);
  int u = 0;
  while (v >= 1024 && u < 4) {
    v /= 1024;
    ++u;
  }
  return u == 0 ? Printf("%llu B", static_cast<unsigned long long>(bytes))
                : Printf("%.1f %s", v, units[u]);
}

std::string HumanDuration(double seconds) {
  const long s = static_cast<long>(seconds);
  if (s < 60) return Printf("%.1f s", seconds);
  if (s < 3600) return Printf("%ldm %02lds", s / 60, s % 60);
  if (s < 86400) return Printf("%ldh %02ldm", s / 3600, (s / 60) % 60);
  return Printf("%ldd %02ldh", s / 86400, (s / 3600) % 24);
}

}  // namespace

bool ParseOutputFormat(const std::string& name, OutputFormat* out) {
  if (name == "table")
    *out = OutputFormat::kTable;
  else if (name == "json")
    *out = OutputFormat::kJson;
  else if (name == "geojson")
    *out = OutputFormat::kGeoJson;
  else if (name == "svg")
    *out = OutputFormat::kSvg;
  else
    return false;
  return true;
}

OutputFormat GuessOutputFormat(const std::string& path, OutputFormat fallback) {
  auto ends_with = [&path](const std::string& suffix) {
    return path.size() >= suffix.size() &&
           path.compare(path.size() - suffix.size(), suffix.size(), suffix) == 0;
  };
  if (ends_with(".geojson")) return OutputFormat::kGeoJson;
  if (ends_with(".json")) return OutputFormat::kJson;
  if (ends_with(".svg")) return OutputFormat::kSvg;
  return fallback;
}

bool HasOutputExtension(const std::string& path) {
  for (const char* suffix : {".geojson", ".json", ".svg", ".txt"}) {
    const std::string s = suffix;
    if (path.size() >= s.size() && path.compare(path.size() - s.size(), s.size(), s) == 0) {
      return true;
    }
  }
  return false;
}

std::string KindName(pb::FeatureKind kind) {
  switch (kind) {
    case pb::FEATURE_KIND_LINE:
      return "line";
    case pb::FEATURE_KIND_PLANE:
      return "plane";
    default:
      return "any";
  }
}

namespace {

// The protobuf JSON mapping writes 64-bit integers as strings ("id": "7");
// mapctl's other JSON (features, watch) writes numbers. Every --json output
// writes numbers: this turns the strings of 64-bit fields of `descriptor`
// back into numbers, in nested messages and repeated fields too.
void SixtyFourBitFieldsAsNumbers(const google::protobuf::Descriptor* descriptor,
                                 nlohmann::ordered_json* object) {
  using google::protobuf::FieldDescriptor;
  if (!object->is_object()) return;
  for (int i = 0; i < descriptor->field_count(); ++i) {
    const FieldDescriptor* field = descriptor->field(i);
    auto it = object->find(field->name());
    if (it == object->end()) continue;
    const auto convert = [field](nlohmann::ordered_json* v) {
      if (field->cpp_type() == FieldDescriptor::CPPTYPE_MESSAGE) {
        if (!field->is_map()) SixtyFourBitFieldsAsNumbers(field->message_type(), v);
        return;
      }
      if (!v->is_string()) return;
      const std::string text = v->get<std::string>();
      try {
        if (field->cpp_type() == FieldDescriptor::CPPTYPE_INT64) *v = std::stoll(text);
        if (field->cpp_type() == FieldDescriptor::CPPTYPE_UINT64) *v = std::stoull(text);
      } catch (const std::exception&) {
        // Not a number: left as written.
      }
    };
    if (field->is_repeated() && it->is_array()) {
      for (auto& element : *it) convert(&element);
    } else {
      convert(&*it);
    }
  }
}

}  // namespace

std::string MessageToJson(const google::protobuf::Message& message) {
  google::protobuf::util::JsonPrintOptions options;
  options.always_print_primitive_fields = true;
  options.preserve_proto_field_names = true;
  std::string out;
  if (!google::protobuf::util::MessageToJsonString(message, &out, options).ok()) return "{}\n";
  nlohmann::ordered_json doc = nlohmann::ordered_json::parse(out, nullptr, false);
  if (doc.is_discarded()) return out + "\n";
  SixtyFourBitFieldsAsNumbers(message.GetDescriptor(), &doc);
  return doc.dump(2, ' ', false, nlohmann::json::error_handler_t::replace) + "\n";
}

std::string FormatFeatureTable(const FeatureList& features, const PlaneList& planes) {
  std::string out = Printf("%-8s %-5s %21s %21s %7s %15s %7s %7s  %s\n", "ID", "KIND", "A (x, y) m",
                           "B (x, y) m", "LEN m", "Z m", "SUPPORT", "MEMBERS", "ROBOTS");
  for (const pb::FusedFeature& f : features) {
    const double length = std::hypot(f.b().x() - f.a().x(), f.b().y() - f.a().y());
    out += Printf("%-8llu %-5s %21s %21s %7.2f %15s %7u %7u  %s\n",
                  static_cast<unsigned long long>(f.id()), KindName(f.kind()).c_str(),
                  Printf("(%.2f, %.2f)", f.a().x(), f.a().y()).c_str(),
                  Printf("(%.2f, %.2f)", f.b().x(), f.b().y()).c_str(), length,
                  Printf("%.2f..%.2f", f.z_min(), f.z_max()).c_str(), f.support(), f.member_count(),
                  Join(f.robots(), ",").c_str());
  }
  out += Printf("%zu feature%s\n", features.size(), features.size() == 1 ? "" : "s");
  if (planes.empty()) return out;
  out += Printf("\n%-8s %-24s %9s %9s %15s %7s %7s  %s\n", "PLANE", "NORMAL (x, y, z)", "OFFSET m",
                "AREA m2", "Z m", "SUPPORT", "MEMBERS", "ROBOTS");
  for (const pb::FusedPlane& p : planes) {
    out += Printf(
        "%-8llu %-24s %9.3f %9.2f %15s %7u %7u  %s\n", static_cast<unsigned long long>(p.id()),
        Printf("(%.3f, %.3f, %.3f)", p.normal().x(), p.normal().y(), p.normal().z()).c_str(),
        p.offset(), p.area(), Printf("%.2f..%.2f", p.z_min(), p.z_max()).c_str(), p.support(),
        p.member_count(), Join(p.robots(), ",").c_str());
  }
  out += Printf("%zu plane%s\n", planes.size(), planes.size() == 1 ? "" : "s");
  return out;
}

std::string FormatFeatureJson(const FeatureList& features, uint64_t map_version,
                              const PlaneList& planes, uint64_t fusion_pending) {
  pb::FeatureMapPage page;
  for (const pb::FusedFeature& f : features) *page.add_features() = f;
  for (const pb::FusedPlane& p : planes) *page.add_planes() = p;
  page.set_total(features.size());
  page.set_map_version(map_version);
  page.set_fusion_pending(fusion_pending);
  return MessageToJson(page);
}

std::string FormatGeoJson(const FeatureList& features, const PlaneList& planes) {
  // ordered_json keeps the keys in the order written (type, id, geometry, properties).
  using Json = nlohmann::ordered_json;
  const auto point = [](double x, double y) { return Json::array({JsonNumber(x), JsonNumber(y)}); };
  const auto robots = [](const google::protobuf::RepeatedPtrField<std::string>& names) {
    return Json(std::vector<std::string>(names.begin(), names.end()));
  };
  Json items = Json::array();
  for (const pb::FusedFeature& f : features) {
    items.push_back({{"type", "Feature"},
                     {"id", f.id()},
                     {"geometry",
                      {{"type", "LineString"},
                       {"coordinates",
                        Json::array({point(f.a().x(), f.a().y()), point(f.b().x(), f.b().y())})}}},
                     {"properties",
                      {{"id", f.id()},
                       {"kind", KindName(f.kind())},
                       {"support", f.support()},
                       {"member_count", f.member_count()},
                       {"z_min", JsonNumber(f.z_min())},
                       {"z_max", JsonNumber(f.z_max())},
                       {"robots", robots(f.robots())}}}});
  }
  for (const pb::FusedPlane& p : planes) {
    // A closed ring: the first point again at the end.
    Json ring = Json::array();
    for (int k = 0; k <= p.boundary_size() && p.boundary_size() > 0; ++k) {
      const pb::Vec3& v = p.boundary(k % p.boundary_size());
      ring.push_back(point(v.x(), v.y()));
    }
    items.push_back(
        {{"type", "Feature"},
         {"id", p.id()},
         {"geometry", {{"type", "Polygon"}, {"coordinates", Json::array({ring})}}},
         {"properties",
          {{"id", p.id()},
           {"kind", "plane"},
           {"normal", Json::array({JsonNumber(p.normal().x()), JsonNumber(p.normal().y()),
                                   JsonNumber(p.normal().z())})},
           {"offset_m", JsonNumber(p.offset())},
           {"area_m2", JsonNumber(p.area())},
           {"z_min", JsonNumber(p.z_min())},
           {"z_max", JsonNumber(p.z_max())},
           {"support", p.support()},
           {"member_count", p.member_count()},
           {"robots", robots(p.robots())}}}});
  }
  const Json doc = {{"type", "FeatureCollection"},
                    {"properties",
                     {{"frame", "map"},
                      {"units", "m"},
                      {"note", "coordinates are map-frame metres (x, y), not longitude/latitude"}}},
                    {"features", std::move(items)}};
  // Invalid UTF-8 in a robot name is replaced rather than aborting the export.
  return doc.dump(2, ' ', false, nlohmann::json::error_handler_t::replace) + "\n";
}

std::string FormatTrailsGeoJson(const std::vector<pb::SessionTrail>& trails) {
  using Json = nlohmann::ordered_json;
  Json items = Json::array();
  for (const pb::SessionTrail& t : trails) {
    if (t.poses().empty()) continue;
    Json coordinates = Json::array();
    for (const pb::TrailPose& p : t.poses()) {
      coordinates.push_back(
          Json::array({JsonNumber(p.position().x()), JsonNumber(p.position().y())}));
    }
    // A LineString needs two positions: one pose is a Point.
    const bool single = coordinates.size() == 1;
    items.push_back({{"type", "Feature"},
                     {"geometry",
                      {{"type", single ? "Point" : "LineString"},
                       {"coordinates", single ? coordinates[0] : coordinates}}},
                     {"properties",
                      {{"robot_id", t.robot_id()},
                       {"session_id", t.session_id()},
                       {"frame", t.frame_tied() ? "map" : "session"},
                       {"poses", t.poses_size()},
                       {"stored_poses", t.stored_poses()},
                       {"first_stamp_ns", t.poses(0).stamp_ns()},
                       {"last_stamp_ns", t.poses(t.poses_size() - 1).stamp_ns()}}}});
  }
  const Json doc = {
      {"type", "FeatureCollection"},
      {"properties",
       {{"units", "m"},
        {"note",
         "coordinates are metres (x, y) in the map frame, or in the session's own frame where "
         "a feature's frame is \"session\" (not yet tied by a merge); not longitude/latitude"}}},
      {"features", std::move(items)}};
  return doc.dump(2, ' ', false, nlohmann::json::error_handler_t::replace) + "\n";
}

std::string FormatStats(const pb::Stats& s, const std::string& server) {
  std::string out = Printf("mapd %s at %s\n", s.version().c_str(), server.c_str());
  auto row = [&out](const char* name, const std::string& value) {
    out += Printf("  %-16s %s\n", name, value.c_str());
  };
  auto num = [](uint64_t v) { return std::to_string(v); };
  row("uptime", HumanDuration(s.uptime_s()));
  row("database",
      (s.db_path().empty() ? std::string("(path shown to operators)") : Visible(s.db_path())) +
          " (" + HumanBytes(s.db_size_bytes()) +
          (s.raw_features() > 0 ? Printf(", %.0f bytes per raw feature", s.bytes_per_raw_feature())
                                : std::string()) +
          ")");
  if (s.recovering()) row("state", "RECOVERING the fused map (health NOT_SERVING)");
  if (s.replaying()) {
    row("state",
        "SERVING, replaying the observations stored after the last snapshot (the map "
        "catches up as the fusion backlog falls)");
  }
  if (!s.write_failure().empty())
    row("state", "NOT WRITABLE (health NOT_SERVING): " + s.write_failure());
  row("robots", num(s.robots()));
  row("sessions", num(s.sessions()));
  row("batches", num(s.batches()));
  row("raw features", num(s.raw_features()));
  row("fused features", num(s.fused_features()) + " published, " + num(s.clusters()) + " clusters");
  if (s.retired_walls() > 0) {
    row("retired walls",
        num(s.retired_walls()) + " (seen through since last seen; back when seen again)");
  }
  row("fusion backlog", num(s.fusion_backlog()) + " observations stored, not fused yet");
  for (const pb::RobotFusionShare& r : s.fusion_shares()) {
    if (r.refused() == 0) continue;
    row("throttled robot", r.robot_id() + ": " + num(r.refused()) +
                               " batches refused (it kept the fuser busy: " + num(r.pending()) +
                               " observations waiting, " +
                               Printf("%.2f ms", 1e3 * r.cost_per_obs_s()) + " of fusion each)");
  }
  row("fused planes", num(s.fused_planes()) + " published (floors, ceilings, ramps)");
  row("fusion nodes", num(s.fusion_nodes()) + " (representatives kept for " +
                          num(s.fused_raw_features()) + " fused raw features)");
  row("submaps", num(s.submaps()));
  row("map version", num(s.map_version()));
  row("snapshot", s.snapshot_age_s() > 0
                      ? Printf("%s old, %llu observations to replay on restart",
                               HumanDuration(s.snapshot_age_s()).c_str(),
                               static_cast<unsigned long long>(s.replay_length()))
                      : Printf("none yet, %llu observations to replay on restart",
                               static_cast<unsigned long long>(s.replay_length())));
  row("ingest rate", Printf("%.1f batches/s, %.1f features/s (last 10 s)", s.ingest_batches_per_s(),
                            s.ingest_features_per_s()));
  return out;
}

std::string FormatRobots(const pb::ListRobotsResponse& robots, int64_t now_ns) {
  std::string out = Printf("%-24s %8s %9s %10s %-6s %-20s %s\n", "ROBOT", "SESSIONS", "BATCHES",
                           "FEATURES", "FRAME", "FIRST SEEN (UTC)", "LAST SEEN");
  for (const pb::RobotInfo& r : robots.robots()) {
    std::string last = IsoTime(r.last_seen_ns());
    if (now_ns > 0 && r.last_seen_ns() > 0 && now_ns >= r.last_seen_ns()) {
      last += " (" + HumanDuration(static_cast<double>(now_ns - r.last_seen_ns()) * 1e-9) + " ago)";
    }
    out += Printf("%-24s %8u %9llu %10llu %-6s %-20s %s\n", r.robot_id().c_str(), r.sessions(),
                  static_cast<unsigned long long>(r.batches()),
                  static_cast<unsigned long long>(r.features()), r.frame_tied() ? "map" : "local",
                  IsoTime(r.first_seen_ns()).c_str(), last.c_str());
  }
  out += Printf("%d robot%s\n", robots.robots_size(), robots.robots_size() == 1 ? "" : "s");
  return out;
}

std::string FormatSubmaps(const pb::ListSubmapsResponse& submaps) {
  // Uploads first; merged maps (merge outputs, never merge inputs) apart.
  const auto table = [&](bool merged) {
    std::string out = Printf("%-6s %-16s %-20s %-4s %7s %10s %10s %10s\n", "ID", "ROBOT", "NAME",
                             "FMT", "RES m", "OCCUPIED", "FREE", "SIZE");
    int n = 0;
    for (const pb::SubmapInfo& m : submaps.submaps()) {
      if (m.merged() != merged) continue;
      ++n;
      out += Printf(
          "%-6llu %-16s %-20s %-4s %7.3f %10llu %10llu %10s\n",
          static_cast<unsigned long long>(m.id()), Visible(m.robot_id()).c_str(),
          Visible(m.name()).c_str(), m.format() == pb::SUBMAP_FORMAT_OCTOMAP_OT ? "ot" : "bt",
          m.resolution(), static_cast<unsigned long long>(m.occupied_voxels()),
          static_cast<unsigned long long>(m.free_voxels()), HumanBytes(m.size_bytes()).c_str());
    }
    return std::make_pair(out, n);
  };
  const auto [uploads, n_uploads] = table(false);
  const auto [merged, n_merged] = table(true);
  std::string out = uploads;
  out += Printf("%d uploaded submap%s\n", n_uploads, n_uploads == 1 ? "" : "s");
  if (n_merged > 0) {
    out += "\nmerged maps (outputs of merges: downloadable, never merge inputs)\n" + merged;
    out += Printf("%d merged map%s\n", n_merged, n_merged == 1 ? "" : "s");
  }
  return out;
}

namespace {

using Json = nlohmann::ordered_json;

Json Vec2Json(const pb::Vec2& v) {
  return Json{{"x", JsonNumber(v.x())}, {"y", JsonNumber(v.y())}};
}

Json FeatureJson(const pb::FusedFeature& f) {
  return Json{{"id", f.id()},
              {"kind", KindName(f.kind())},
              {"a", Vec2Json(f.a())},
              {"b", Vec2Json(f.b())},
              {"z_min", JsonNumber(f.z_min())},
              {"z_max", JsonNumber(f.z_max())},
              {"support", f.support()},
              {"member_count", f.member_count()},
              {"robots", std::vector<std::string>(f.robots().begin(), f.robots().end())}};
}

Json PlaneJson(const pb::FusedPlane& p) {
  Json boundary = Json::array();
  for (const pb::Vec3& v : p.boundary()) {
    boundary.push_back({JsonNumber(v.x()), JsonNumber(v.y()), JsonNumber(v.z())});
  }
  return Json{
      {"id", p.id()},
      {"normal",
       {JsonNumber(p.normal().x()), JsonNumber(p.normal().y()), JsonNumber(p.normal().z())}},
      {"offset_m", JsonNumber(p.offset())},
      {"area_m2", JsonNumber(p.area())},
      {"z_min", JsonNumber(p.z_min())},
      {"z_max", JsonNumber(p.z_max())},
      {"support", p.support()},
      {"member_count", p.member_count()},
      {"robots", std::vector<std::string>(p.robots().begin(), p.robots().end())},
      {"boundary", boundary}};
}

std::string FeatureText(const pb::FusedFeature& f) {
  return Printf("%s (%.2f, %.2f)-(%.2f, %.2f) support %u robots %s", KindName(f.kind()).c_str(),
                f.a().x(), f.a().y(), f.b().x(), f.b().y(), f.support(),
                Join(f.robots(), ",").c_str());
}

std::string PlaneText(const pb::FusedPlane& p) {
  return Printf("normal (%.3f, %.3f, %.3f) offset %.3f area %.2f m2 support %u robots %s",
                p.normal().x(), p.normal().y(), p.normal().z(), p.offset(), p.area(), p.support(),
                Join(p.robots(), ",").c_str());
}

}  // namespace

std::string FormatDeltaLines(const pb::FeatureMapDelta& delta, bool json) {
  const uint64_t v = delta.map_version();
  std::string out;
  auto line = [&](const char* change, const char* type, uint64_t id, const Json* body,
                  const std::string& text) {
    if (json) {
      Json j{{"map_version", v}, {"change", change}};
      if (type != nullptr) {
        j["type"] = type;
        j["id"] = id;
      }
      if (body != nullptr) j[type] = *body;
      out += j.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace) + "\n";
    } else {
      out += Printf("v=%llu %s", static_cast<unsigned long long>(v), change);
      if (type != nullptr) out += Printf(" %s %llu", type, static_cast<unsigned long long>(id));
      if (!text.empty()) out += " " + text;
      out += "\n";
    }
  };
  if (delta.resync()) line("resync", nullptr, 0, nullptr, "(the full map follows)");
  for (const auto* list : {&delta.added(), &delta.updated()}) {
    const char* change = list == &delta.added() ? "added" : "updated";
    for (const pb::FusedFeature& f : *list) {
      const Json body = FeatureJson(f);
      line(change, "feature", f.id(), &body, FeatureText(f));
    }
  }
  for (uint64_t id : delta.removed()) line("removed", "feature", id, nullptr, "");
  for (const auto* list : {&delta.added_planes(), &delta.updated_planes()}) {
    const char* change = list == &delta.added_planes() ? "added" : "updated";
    for (const pb::FusedPlane& p : *list) {
      const Json body = PlaneJson(p);
      line(change, "plane", p.id(), &body, PlaneText(p));
    }
  }
  for (uint64_t id : delta.removed_planes()) line("removed", "plane", id, nullptr, "");
  return out;
}

}  // namespace mapd::client
