#include "service/config.h"

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <functional>
#include <map>
#include <sstream>

namespace mapd::service {
namespace {

constexpr double kDegToRad = 3.14159265358979323846 / 180.0;

Status ParseDouble(const std::string& key, const std::string& v, double* out) {
  char* end = nullptr;
  const double d = std::strtod(v.c_str(), &end);
  if (v.empty() || *end != '\0' || !std::isfinite(d)) {
    return Status::InvalidArgument(key + ": '" + v + "' is not a finite number");
  }
  *out = d;
  return Status::Ok();
}

template <typename T>
Status ParseUnsigned(const std::string& key, const std::string& v, T* out) {
  char* end = nullptr;
  const unsigned long long u = std::strtoull(v.c_str(), &end, 10);
  if (v.empty() || *end != '\0' || v[0] == '-') {
    return Status::InvalidArgument(key + ": '" + v + "' is not a non-negative integer");
  }
  *out = static_cast<T>(u);
  return Status::Ok();
}

Status ParseBool(const std::string& key, const std::string& v, bool* out) {
  if (v == "true" || v == "1" || v == "yes") return *out = true, Status::Ok();
  if (v == "false" || v == "0" || v == "no") return *out = false, Status::Ok();
  return Status::InvalidArgument(key + ": '" + v + "' is not true or false");
}

using Setter = std::function<Status(const std::string& key, const std::string& v, ServerConfig* c)>;

struct Setting {
  Setter set;
  const char* help;
};

const std::map<std::string, Setting>& Settings() {
  static const std::map<std::string, Setting> kSettings = {
      {"listen", {[](auto&, auto& v, auto* c) { c->listen = v; return Status::Ok(); },
                  "host:port to serve on (default 127.0.0.1:50051; port 0 = any free port)"}},
      {"db", {[](auto&, auto& v, auto* c) { c->db_path = v; return Status::Ok(); },
              "SQLite database file (default $MAPD_DATA_DIR/map.db or ~/.local/share/mapd/map.db)"}},
      {"sync", {[](auto& k, auto& v, auto* c) {
                  if (v != "normal" && v != "full") return Status::InvalidArgument(k + ": use normal or full");
                  c->sync_full = v == "full";
                  return Status::Ok();
                },
                "normal (survives a crash of mapd) or full (survives power loss; slower)"}},
      {"busy_timeout_ms", {[](auto& k, auto& v, auto* c) { return ParseUnsigned(k, v, &c->busy_timeout_ms); },
                           "how long a commit waits for a database lock held by another process, ms (5000)"}},
      {"fusion.mode", {[](auto&, auto& v, auto* c) { return fusion::ParseFusionMode(v, &c->fusion.mode); },
                       "bounded (work and memory follow the map, not its history) or exact (the "
                       "paper's batch result; cost grows with every feature ever seen) (bounded)"}},
      {"fusion.cover_m", {[](auto& k, auto& v, auto* c) { return ParseDouble(k, v, &c->fusion.cover_m); },
                          "bounded mode: a feature within this of a representative of an established "
                          "cluster is folded into it, metres (0.02)"}},
      {"snapshot.every_observations",
       {[](auto& k, auto& v, auto* c) { return ParseUnsigned(k, v, &c->snapshot_every_observations); },
        "snapshot the fusion state after this many fused observations; a restart replays only "
        "what came after the newest snapshot; 0 = never (20000)"}},
      {"snapshot.max_age_s", {[](auto& k, auto& v, auto* c) { return ParseDouble(k, v, &c->snapshot_max_age_s); },
                              "... or once the newest snapshot is this old and the map changed, seconds (60)"}},
      {"storage.raw_retention_days",
       {[](auto& k, auto& v, auto* c) { return ParseDouble(k, v, &c->raw_retention_days); },
        "drop raw observations older than this once every kept snapshot reflects them (never "
        "those of a session not yet tied); the map and restarts are unchanged, but a change of "
        "fusion parameters can only replay what is left; days, 0 = keep forever (0)"}},
      {"fusion.delta_deg", {[](auto& k, auto& v, auto* c) {
                              double d;
                              MAPD_RETURN_IF_ERROR(ParseDouble(k, v, &d));
                              c->fusion.delta_rad = d * kDegToRad;
                              return Status::Ok();
                            },
                            "criterion 1: max included angle, degrees (5)"}},
      {"fusion.gamma", {[](auto& k, auto& v, auto* c) { return ParseDouble(k, v, &c->fusion.gamma); },
                        "criterion 2: min feature-circle overlap ratio, [0, 1] (0.3)"}},
      {"fusion.eta_m", {[](auto& k, auto& v, auto* c) { return ParseDouble(k, v, &c->fusion.eta_m); },
                        "criterion 3: max centre-to-segment distance, metres (0.3)"}},
      {"fusion.min_support", {[](auto& k, auto& v, auto* c) { return ParseUnsigned(k, v, &c->fusion.min_support); },
                              "observations a fused feature needs to be published (3)"}},
      {"fusion.snap_m", {[](auto& k, auto& v, auto* c) { return ParseDouble(k, v, &c->fusion.snap_m); },
                         "corner optimisation: endpoints closer than this meet, metres (0.5)"}},
      {"fusion.corner_mode", {[](auto&, auto& v, auto* c) { return fusion::ParseCornerMode(v, &c->fusion.corner_mode); },
                              "midpoint or intersection (intersection)"}},
      {"fusion.max_plane_tilt_deg", {[](auto& k, auto& v, auto* c) {
                                       double d;
                                       MAPD_RETURN_IF_ERROR(ParseDouble(k, v, &d));
                                       c->fusion.max_plane_tilt_rad = d * kDegToRad;
                                       return Status::Ok();
                                     },
                                     "planes tilted less than this from vertical become walls, degrees (10)"}},
      {"limits.max_features_per_batch",
       {[](auto& k, auto& v, auto* c) { return ParseUnsigned(k, v, &c->ingest.limits.max_features_per_batch); },
        "lines + planes in one batch (1024, at most 4096)"}},
      {"limits.max_boundary_points",
       {[](auto& k, auto& v, auto* c) { return ParseUnsigned(k, v, &c->ingest.limits.max_boundary_points); },
        "boundary points of one plane (1024)"}},
      {"limits.max_in_flight", {[](auto& k, auto& v, auto* c) { return ParseUnsigned(k, v, &c->ingest.max_in_flight); },
                                "unacknowledged batches per stream before reading pauses (1024)"}},
      {"limits.max_message_bytes", {[](auto& k, auto& v, auto* c) { return ParseUnsigned(k, v, &c->max_message_bytes); },
                                    "largest gRPC message accepted, bytes (16777216)"}},
      {"limits.max_group_batches", {[](auto& k, auto& v, auto* c) { return ParseUnsigned(k, v, &c->max_group_batches); },
                                    "batches committed in one transaction at most (4096)"}},
      {"limits.max_submap_bytes",
       {[](auto& k, auto& v, auto* c) { return ParseUnsigned(k, v, &c->submaps.max_submap_bytes); },
        "largest submap file accepted by UploadSubmap, bytes (67108864)"}},
      {"limits.max_concurrent_merges",
       {[](auto& k, auto& v, auto* c) { return ParseUnsigned(k, v, &c->submaps.max_concurrent_merges); },
        "submap merges computed at once (1, at most 64)"}},
      {"limits.max_queued_merges",
       {[](auto& k, auto& v, auto* c) { return ParseUnsigned(k, v, &c->submaps.max_queued_merges); },
        "merges waiting for a slot; beyond it MergeSubmaps answers RESOURCE_EXHAUSTED (4)"}},
      {"merge.min_matched_corners",
       {[](auto& k, auto& v, auto* c) { return ParseUnsigned(k, v, &c->submaps.min_matched_corners); },
        "matched corners a pairwise merge needs to be accepted (4, at least 3)"}},
      {"merge.max_residual_voxels",
       {[](auto& k, auto& v, auto* c) { return ParseDouble(k, v, &c->submaps.max_residual_voxels); },
        "largest accepted RMS residual after ICP, voxels of the finer map (2)"}},
      {"merge.min_overlap_score",
       {[](auto& k, auto& v, auto* c) { return ParseDouble(k, v, &c->submaps.min_overlap_score); },
        "smallest accepted overlap score, [0, 1] (0.3)"}},
      {"merge.max_seconds",
       {[](auto& k, auto& v, auto* c) { return ParseDouble(k, v, &c->submaps.max_merge_seconds); },
        "time budget of one merge, seconds (60)"}},
      {"merge.resolution_policy", {[](auto& k, auto& v, auto* c) {
                                     if (v != "refuse" && v != "resample") {
                                       return Status::InvalidArgument(k + ": use refuse or resample");
                                     }
                                     c->submaps.resample_resolutions = v == "resample";
                                     return Status::Ok();
                                   },
                                   "submaps of different resolutions: refuse or resample (to the finest) (refuse)"}},
      {"merge.fusion_rule", {[](auto& k, auto& v, auto* c) {
                               if (v != "overlap" && v != "log_odds") {
                                 return Status::InvalidArgument(k + ": use overlap or log_odds");
                               }
                               c->submaps.log_odds_fusion = v == "log_odds";
                               return Status::Ok();
                             },
                             "occupancy fusion: overlap (the paper's rule) or log_odds (overlap)"}},
      {"shutdown_grace_s", {[](auto& k, auto& v, auto* c) { return ParseDouble(k, v, &c->shutdown_grace_s); },
                            "on SIGTERM, seconds streams get to finish (5)"}},
      {"tls_cert", {[](auto&, auto& v, auto* c) { c->tls_cert = v; return Status::Ok(); },
                    "PEM certificate chain; TLS is required off loopback"}},
      {"tls_key", {[](auto&, auto& v, auto* c) { c->tls_key = v; return Status::Ok(); }, "PEM private key"}},
      {"allow_insecure_remote", {[](auto& k, auto& v, auto* c) { return ParseBool(k, v, &c->allow_insecure_remote); },
                                 "serve plaintext on a non-loopback address anyway (false)"}},
      {"log_level", {[](auto& k, auto& v, auto* c) {
                       if (v != "debug" && v != "info" && v != "warn" && v != "error") {
                         return Status::InvalidArgument(k + ": use debug, info, warn or error");
                       }
                       c->log_level = v;
                       return Status::Ok();
                     },
                     "debug, info, warn or error (info)"}},
  };
  return kSettings;
}

std::string Trim(const std::string& s) {
  const size_t b = s.find_first_not_of(" \t\r");
  if (b == std::string::npos) return "";
  const size_t e = s.find_last_not_of(" \t\r");
  return s.substr(b, e - b + 1);
}

bool IsLoopback(const std::string& listen) {
  return listen.rfind("127.", 0) == 0 || listen.rfind("localhost:", 0) == 0 ||
         listen.rfind("[::1]:", 0) == 0 || listen.rfind("unix:", 0) == 0;
}

}  // namespace

std::string DefaultDbPath() {
  if (const char* d = std::getenv("MAPD_DATA_DIR"); d && *d) return std::string(d) + "/map.db";
  if (const char* x = std::getenv("XDG_DATA_HOME"); x && *x) return std::string(x) + "/mapd/map.db";
  const char* home = std::getenv("HOME");
  return std::string(home && *home ? home : ".") + "/.local/share/mapd/map.db";
}

Status SubmapOptions::Validate() const {
  if (max_submap_bytes < 64) return Status::InvalidArgument("limits.max_submap_bytes must be >= 64");
  if (max_concurrent_merges < 1 || max_concurrent_merges > 64) {
    return Status::InvalidArgument("limits.max_concurrent_merges must be in [1, 64]");
  }
  if (max_queued_merges > 1024) return Status::InvalidArgument("limits.max_queued_merges must be <= 1024");
  if (min_matched_corners < 3) {
    return Status::InvalidArgument("merge.min_matched_corners must be >= 3 (a rigid transform needs 3)");
  }
  if (!(max_residual_voxels > 0) || !std::isfinite(max_residual_voxels)) {
    return Status::InvalidArgument("merge.max_residual_voxels must be finite and > 0");
  }
  if (!(min_overlap_score >= 0 && min_overlap_score <= 1)) {
    return Status::InvalidArgument("merge.min_overlap_score must be in [0, 1]");
  }
  if (!(max_merge_seconds > 0) || !std::isfinite(max_merge_seconds)) {
    return Status::InvalidArgument("merge.max_seconds must be finite and > 0");
  }
  return Status::Ok();
}

Status ServerConfig::Validate() const {
  Status f = fusion.Validate();
  if (!f.ok()) return Status::InvalidArgument("fusion: " + f.message());
  Status l = ingest.limits.Validate();
  if (!l.ok()) return Status::InvalidArgument("limits: " + l.message());
  if (ingest.max_in_flight == 0) return Status::InvalidArgument("limits.max_in_flight must be >= 1");
  if (max_group_batches == 0) return Status::InvalidArgument("limits.max_group_batches must be >= 1");
  if (!(raw_retention_days >= 0) || !std::isfinite(raw_retention_days)) {
    return Status::InvalidArgument("storage.raw_retention_days must be finite and >= 0");
  }
  if (!(snapshot_max_age_s > 0) || !std::isfinite(snapshot_max_age_s)) {
    return Status::InvalidArgument("snapshot.max_age_s must be finite and > 0");
  }
  if (max_message_bytes < 1024) return Status::InvalidArgument("limits.max_message_bytes must be >= 1024");
  if (listen.empty() || listen.find(':') == std::string::npos) {
    return Status::InvalidArgument("listen: '" + listen + "' is not host:port");
  }
  if (tls_cert.empty() != tls_key.empty()) {
    return Status::InvalidArgument("tls_cert and tls_key must be given together");
  }
  if (!IsLoopback(listen) && tls_cert.empty() && !allow_insecure_remote) {
    return Status::InvalidArgument("listen: '" + listen +
                                   "' is not loopback; give tls_cert and tls_key, or "
                                   "allow_insecure_remote=true on a trusted network");
  }
  if (!(shutdown_grace_s >= 0)) return Status::InvalidArgument("shutdown_grace_s must be >= 0");
  return submaps.Validate();
}

Status ApplySetting(const std::string& key, const std::string& value, ServerConfig* config) {
  auto it = Settings().find(key);
  if (it == Settings().end()) return Status::InvalidArgument("unknown setting '" + key + "' (see mapd --help)");
  return it->second.set(key, value, config);
}

Status LoadConfigFile(const std::string& path, ServerConfig* config) {
  std::ifstream in(path);
  if (!in) return Status::NotFound("cannot read config file '" + path + "'");
  std::string line;
  for (int n = 1; std::getline(in, line); ++n) {
    line = Trim(line.substr(0, line.find('#')));
    if (line.empty()) continue;
    const size_t eq = line.find('=');
    if (eq == std::string::npos) {
      return Status::InvalidArgument(path + ":" + std::to_string(n) + ": expected key = value");
    }
    Status s = ApplySetting(Trim(line.substr(0, eq)), Trim(line.substr(eq + 1)), config);
    if (!s.ok()) return Status::InvalidArgument(path + ":" + std::to_string(n) + ": " + s.message());
  }
  return Status::Ok();
}

Status ParseFlags(const std::vector<std::string>& args, ServerConfig* config, bool* help) {
  *help = false;
  // The config file first, so that flags override it wherever they stand.
  std::vector<std::pair<std::string, std::string>> settings;
  for (size_t i = 0; i < args.size(); ++i) {
    const std::string& a = args[i];
    if (a == "--help" || a == "-h") {
      *help = true;
      return Status::Ok();
    }
    if (a.rfind("--", 0) != 0) return Status::InvalidArgument("unexpected argument '" + a + "'");
    std::string key = a.substr(2), value;
    if (const size_t eq = key.find('='); eq != std::string::npos) {
      value = key.substr(eq + 1);
      key = key.substr(0, eq);
    } else if (i + 1 < args.size()) {
      value = args[++i];
    } else {
      return Status::InvalidArgument("--" + key + " needs a value");
    }
    if (key == "config") {
      MAPD_RETURN_IF_ERROR(LoadConfigFile(value, config));
    } else {
      settings.emplace_back(key, value);
    }
  }
  for (const auto& [k, v] : settings) MAPD_RETURN_IF_ERROR(ApplySetting(k, v, config));
  return config->Validate();
}

std::string FlagsHelp() {
  std::ostringstream out;
  out << "usage: mapd [--config FILE] [--KEY VALUE | --KEY=VALUE ...]\n\n"
         "Serves the mapserver.v1 gRPC API. Every KEY may also be set in the config file as\n"
         "'KEY = VALUE'; flags override the file.\n\n";
  out << "  --config FILE\n      read settings from FILE first\n";
  for (const auto& [key, s] : Settings()) out << "  --" << key << "\n      " << s.help << "\n";
  return out.str();
}

}  // namespace mapd::service
