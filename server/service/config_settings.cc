#include "service/config_settings.h"

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <type_traits>
#include <utility>

namespace mapd::service {
namespace {

constexpr double kDegToRad = 3.14159265358979323846 / 180.0;
constexpr double kInf = std::numeric_limits<double>::infinity();

template <typename T>
using Ref = T& (*)(ServerConfig&);

template <typename F>
const auto& Read(F ref, const ServerConfig& c) {
  return ref(const_cast<ServerConfig&>(c));  // ref only selects a member
}

// 15 significant digits: 0.3 reads "0.3", degrees converted to radians and
// back read as they were written.
std::string Number(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.15g", v);
  return buf;
}

struct Range {
  double lo;
  double hi;
  bool lo_open = false;  // lo itself is excluded
};

std::string RangeText(const Range& r) {
  return std::string(r.lo_open ? "(" : "[") + Number(r.lo) + ", " +
         (r.hi == kInf ? "inf)" : Number(r.hi) + "]");
}

Status CheckRange(const std::string& key, double v, const Range& r) {
  const bool below = r.lo_open ? !(v > r.lo) : !(v >= r.lo);
  if (std::isnan(v) || below || v > r.hi || (r.hi == kInf && std::isinf(v))) {
    return Status::InvalidArgument(key + " = " + Number(v) + " is outside " + RangeText(r));
  }
  return Status::Ok();
}

// A real number; `scale` converts the written unit to the stored one
// (degrees written, radians stored).
Setting Real(std::string key, std::string help, Ref<double> ref, Range range, double scale = 1.0) {
  help += ", " + RangeText(range);
  return {key,
          "number",
          help,
          [key, ref, range, scale](const std::string& v, ServerConfig* c) {
            char* end = nullptr;
            const double d = std::strtod(v.c_str(), &end);
            if (v.empty() || *end != '\0' || !std::isfinite(d)) {
              return Status::InvalidArgument(key + ": '" + v + "' is not a finite number");
            }
            MAPD_RETURN_IF_ERROR(CheckRange(key, d, range));
            ref(*c) = d * scale;
            return Status::Ok();
          },
          [key, ref, range, scale](const ServerConfig& c) {
            return CheckRange(key, Read(ref, c) / scale, range);
          },
          [ref, scale](const ServerConfig& c) { return Number(Read(ref, c) / scale); }};
}

template <typename F>
Setting Count(std::string key, std::string help, F ref, uint64_t lo, uint64_t hi) {
  using T = std::remove_reference_t<decltype(ref(std::declval<ServerConfig&>()))>;
  help += ", [" + std::to_string(lo) + ", " + std::to_string(hi) + "]";
  auto check = [key, lo, hi](uint64_t u) {
    if (u < lo || u > hi) {
      return Status::InvalidArgument(key + " = " + std::to_string(u) + " is outside [" +
                                     std::to_string(lo) + ", " + std::to_string(hi) + "]");
    }
    return Status::Ok();
  };
  return {key,
          "integer",
          help,
          [key, ref, check](const std::string& v, ServerConfig* c) {
            char* end = nullptr;
            errno = 0;
            const unsigned long long u = std::strtoull(v.c_str(), &end, 10);
            if (v.empty() || *end != '\0' || v[0] == '-' || v[0] == '+' || errno == ERANGE) {
              return Status::InvalidArgument(key + ": '" + v + "' is not a non-negative integer");
            }
            MAPD_RETURN_IF_ERROR(check(u));
            ref(*c) = static_cast<T>(u);
            return Status::Ok();
          },
          [key, ref, check](const ServerConfig& c) {
            const T v = Read(ref, c);
            if constexpr (std::is_signed_v<T>) {
              if (v < 0)
                return Status::InvalidArgument(key + " = " + std::to_string(v) + " is negative");
            }
            return check(static_cast<uint64_t>(v));
          },
          [ref](const ServerConfig& c) { return std::to_string(Read(ref, c)); }};
}

Setting Flag(std::string key, std::string help, Ref<bool> ref) {
  return {key,
          "bool",
          help,
          [key, ref](const std::string& v, ServerConfig* c) {
            if (v == "true" || v == "1" || v == "yes") return ref(*c) = true, Status::Ok();
            if (v == "false" || v == "0" || v == "no") return ref(*c) = false, Status::Ok();
            return Status::InvalidArgument(key + ": '" + v + "' is not true or false");
          },
          [](const ServerConfig&) { return Status::Ok(); },
          [ref](const ServerConfig& c) { return std::string(Read(ref, c) ? "true" : "false"); }};
}

Setting Text(std::string key, std::string help, Ref<std::string> ref) {
  return {key,
          "text",
          help,
          [ref](const std::string& v, ServerConfig* c) {
            ref(*c) = v;
            return Status::Ok();
          },
          [](const ServerConfig&) { return Status::Ok(); },
          [ref](const ServerConfig& c) { return Read(ref, c); }};
}

// One of a few names, stored as a bool: `names` = {false name, true name}.
Setting Choice(std::string key, std::string help, Ref<bool> ref, std::string when_false,
               std::string when_true) {
  return {key,
          when_false + "|" + when_true,
          help,
          [key, ref, when_false, when_true](const std::string& v, ServerConfig* c) {
            if (v != when_false && v != when_true) {
              return Status::InvalidArgument(key + ": '" + v + "' is neither " + when_false +
                                             " nor " + when_true);
            }
            ref(*c) = v == when_true;
            return Status::Ok();
          },
          [](const ServerConfig&) { return Status::Ok(); },
          [ref, when_false, when_true](const ServerConfig& c) {
            return Read(ref, c) ? when_true : when_false;
          }};
}

}  // namespace

const std::vector<Setting>& Settings() {
  using C = ServerConfig;
  // clang-format off
  static const std::vector<Setting> kSettings = {
      Text("listen", "host:port to serve on; port 0 = any free port. Off loopback, TLS is required",
           [](C& c) -> auto& { return c.listen; }),
      Text("db", "SQLite database file; empty = $MAPD_DATA_DIR/map.db, else $XDG_DATA_HOME/mapd/map.db, "
                 "else ~/.local/share/mapd/map.db",
           [](C& c) -> auto& { return c.db_path; }),
      Text("data_dir", "serve several maps from this directory, one SQLite file <map id>.db each (default.db = "
                       "the default map; CreateMap adds more); not with db",
           [](C& c) -> auto& { return c.data_dir; }),
      Text("store", "serve the maps of a PostgreSQL database: a libpq connection string or postgresql:// URI "
                    "(docs/scale-out.md); the password comes from PGPASSWORD, ~/.pgpass or passfile=, never "
                    "from here; not with db or data_dir",
           [](C& c) -> auto& { return c.store; }),
      Text("advertise_address", "with store: host:port where clients reach this mapd, sent to them in redirects "
                                "(empty = listen, with this host's name if it listens on every interface)",
           [](C& c) -> auto& { return c.advertise_address; }),
      Text("instance_name", "with store: this mapd's name among those serving the database, the same across "
                            "restarts (empty = the advertised address)",
           [](C& c) -> auto& { return c.instance_name; }),
      Real("lease_ttl_s", "with store: how long a map stays with a mapd that stopped renewing its lease before "
                          "another takes it over, seconds",
           [](C& c) -> auto& { return c.lease_ttl_s; }, {0.5, 600}),
      Flag("forward", "with store: relay calls and streams (batches, uploads) for a map another mapd serves to "
                      "it, for clients that know one address (clients that follow redirects are redirected); "
                      "false: redirect every such call",
           [](C& c) -> auto& { return c.forward; }),
      Text("forward_ca", "with store and tls_cert: PEM CA of the other instances' certificates, to forward calls "
                         "to them over TLS (empty: with TLS, calls are redirected; never with tls_client_ca)",
           [](C& c) -> auto& { return c.forward_ca; }),
      Choice("sync", "normal: an acknowledged batch survives a crash of mapd; full: it survives power loss too "
                     "(slower commits)",
             [](C& c) -> auto& { return c.sync_full; }, "normal", "full"),
      Count("busy_timeout_ms", "how long a commit waits for a database lock held by another process, ms",
            [](C& c) -> auto& { return c.busy_timeout_ms; }, 0, 600000),
      Real("shutdown_grace_s", "on SIGTERM, time open streams get to finish, seconds",
           [](C& c) -> auto& { return c.shutdown_grace_s; }, {0, 3600}),
      Real("shutdown_flush_s", "on SIGTERM, after the grace: time to commit what is queued while the database "
           "refuses writes (disk full) before mapd exits without it (never acknowledged, nothing lost), seconds",
           [](C& c) -> auto& { return c.shutdown_flush_s; }, {0, 3600}),
      {"log_level", "debug|info|warn|error", "least severe log line written",
       [](const std::string& v, C* c) {
         if (v != "debug" && v != "info" && v != "warn" && v != "error") {
           return Status::InvalidArgument("log_level: '" + v + "' is not debug, info, warn or error");
         }
         c->log_level = v;
         return Status::Ok();
       },
       [](const C&) { return Status::Ok(); }, [](const C& c) { return c.log_level; }},
      Text("tls_cert", "PEM certificate chain of the server; with tls_key, serves TLS",
           [](C& c) -> auto& { return c.tls_cert; }),
      Text("tls_key", "PEM private key of tls_cert", [](C& c) -> auto& { return c.tls_key; }),
      Flag("allow_insecure_remote", "serve plaintext on a non-loopback address anyway (a trusted network only)",
           [](C& c) -> auto& { return c.allow_insecure_remote; }),
      Flag("auth.required", "every call needs a token (or a client certificate), even before the first token "
           "exists; required off loopback (false: loopback without tokens is open)",
           [](C& c) -> auto& { return c.auth_required; }),
      Text("tls_client_ca", "PEM CA file: clients must present a certificate it signed; its CN is the robot id "
           "(needs tls_cert)", [](C& c) -> auto& { return c.tls_client_ca; }),
      Text("health_listen", "a second, plaintext host:port on loopback where health checks (grpc.health.v1) "
           "need no client certificate under tls_client_ca; other RPCs there need a token; empty = none",
           [](C& c) -> auto& { return c.health_listen; }),

      Count("snapshot.every_observations", "snapshot the fusion state after this many fused observations; "
            "a restart replays only what came after the newest snapshot; 0 = never",
            [](C& c) -> auto& { return c.snapshot_every_observations; }, 0, uint64_t{1} << 40),
      Real("snapshot.max_age_s", "... or once the newest snapshot is this old and the map changed, seconds",
           [](C& c) -> auto& { return c.snapshot_max_age_s; }, {0, 1e7, true}),
      Real("storage.raw_retention_days", "drop raw observations older than this once every kept snapshot "
           "reflects them (never those of a session not yet tied); a change of fusion parameters can then only "
           "replay what is left; days, 0 = keep forever",
           [](C& c) -> auto& { return c.raw_retention_days; }, {0, 1e5}),
      Count("storage.max_db_bytes", "the database file grows to this at most; beyond it writes fail as on a full "
            "disk (health NOT_SERVING, batches refused, nothing acknowledged lost); bytes, 0 = no limit",
            [](C& c) -> auto& { return c.max_db_bytes; }, 0, uint64_t{1} << 50),

      {"fusion.mode", "bounded|exact",
       "bounded: work and memory follow the map, not its history; exact: the paper's batch result, cost grows "
       "with every feature ever seen",
       [](const std::string& v, C* c) { return fusion::ParseFusionMode(v, &c->fusion.mode); },
       [](const C&) { return Status::Ok(); },
       [](const C& c) { return std::string(fusion::FusionModeName(c.fusion.mode)); }},
      Real("fusion.cover_m", "bounded mode: a feature within this of a representative of an established "
           "cluster is folded into it, metres",
           [](C& c) -> auto& { return c.fusion.cover_m; }, {0, 1}),
      Real("fusion.delta_deg", "criterion 1: max included angle, degrees",
           [](C& c) -> auto& { return c.fusion.delta_rad; }, {0, 90, true}, kDegToRad),
      Real("fusion.gamma", "criterion 2: min feature-circle overlap ratio",
           [](C& c) -> auto& { return c.fusion.gamma; }, {0, 1}),
      Real("fusion.eta_m", "criterion 3: max centre-to-segment distance, metres",
           [](C& c) -> auto& { return c.fusion.eta_m; }, {0, 100, true}),
      Count("fusion.min_support", "observations a fused feature needs to be published",
            [](C& c) -> auto& { return c.fusion.min_support; }, 1, 1000000),
      Real("fusion.snap_m", "corner optimisation: endpoints closer than this meet, metres",
           [](C& c) -> auto& { return c.fusion.snap_m; }, {0, 100}),
      {"fusion.corner_mode", "intersection|midpoint",
       "where snapped endpoints meet: the intersection of the two fused lines, or their midpoint (the paper)",
       [](const std::string& v, C* c) { return fusion::ParseCornerMode(v, &c->fusion.corner_mode); },
       [](const C&) { return Status::Ok(); },
       [](const C& c) { return std::string(fusion::CornerModeName(c.fusion.corner_mode)); }},
      {"fusion.corner_pairing", "mutual|greedy",
       "which endpoints snap: mutual nearest neighbours (local), or greedy in wall id order "
       "(docs/fusion.md, \"Corner pairing\")",
       [](const std::string& v, C* c) { return fusion::ParseCornerPairing(v, &c->fusion.corner_pairing); },
       [](const C&) { return Status::Ok(); },
       [](const C& c) { return std::string(fusion::CornerPairingName(c.fusion.corner_pairing)); }},
      Real("fusion.max_plane_tilt_deg", "planes tilted less than this from vertical become walls, degrees",
           [](C& c) -> auto& { return c.fusion.max_plane_tilt_rad; }, {0, 90}, kDegToRad),
      Real("fusion.chain_max_rms_m", "chain guard: a cluster whose member endpoints lie farther than this "
           "(RMS) from its fitted line is published as pieces that each fit a line, never cutting off a piece "
           "below min_support; metres, 0 = off (the paper's method)",
           [](C& c) -> auto& { return c.fusion.chain_max_rms_m; }, {0, 100}),
      Real("fusion.chain_max_sse_ratio", "chain guard: cut only where the pieces keep less than this share of "
           "the squared residual; 0 never cuts",
           [](C& c) -> auto& { return c.fusion.chain_max_sse_ratio; }, {0, 1}),
      Flag("fusion.consolidate", "wall consolidation: published features on one wall (within delta and wall_offset_m, "
           "overlapping or within wall_gap_m) are published as one; false = one feature per cluster (the paper)",
           [](C& c) -> auto& { return c.fusion.consolidate; }),
      Real("fusion.wall_gap_m", "wall consolidation: pieces of one wall this far apart along it still join, metres",
           [](C& c) -> auto& { return c.fusion.wall_gap_m; }, {0, 1000}),
      Real("fusion.wall_offset_m", "wall consolidation: pieces join only if they lie within this of each other's "
           "line, metres",
           [](C& c) -> auto& { return c.fusion.wall_offset_m; }, {0, 100}),
      Real("fusion.wall_occluded_gap_m", "wall consolidation with free-space evidence: pieces of one wall "
           "farther apart than wall_gap_m, up to this, join if no ray was seen to pass through the gap (an "
           "occlusion, not a passage), and a piece crossed by seen-free space joins nothing; metres, 0 = off",
           [](C& c) -> auto& { return c.fusion.wall_occluded_gap_m; }, {0, 1000}),
      Real("fusion.wall_occluded_gap_ratio", "wall consolidation with free-space evidence: an occluded gap "
           "joins only if it is at most this many times the shorter piece's length (an unseen stretch is "
           "not proof of a wall)",
           [](C& c) -> auto& { return c.fusion.wall_occluded_gap_ratio; }, {0, 1000, true}),
      Count("fusion.wall_free_min_count", "wall consolidation with free-space evidence: visibility triangles "
            "(sensor to observed segment) that must cover a 0.25 m cell before it counts as seen free",
            [](C& c) -> auto& { return c.fusion.wall_free_min_count; }, 1, 255),
      Real("fusion.wall_proof_gap_m", "wall consolidation with free-space evidence: an occluded gap up "
           "to this long joins only where an observation saw something in front of it (indoors a short "
           "unseen gap is more often a doorway seen through to clutter); metres, 0 = no proof needed",
           [](C& c) -> auto& { return c.fusion.wall_proof_gap_m; }, {0, 1000}),
      Real("fusion.evidence_range_m", "free-space evidence reaches at most this far from the sensor (a "
           "view of a farther segment is clipped); bounds the cells one observation writes, metres",
           [](C& c) -> auto& { return c.fusion.evidence_range_m; }, {0, 1000, true}),
      Count("fusion.retire_views", "retirement: observations that must see through a cell of a published "
            "wall piece since it was last supported before the cell counts as seen through; 0 = walls "
            "never leave (needs fusion.wall_occluded_gap_m > 0)",
            [](C& c) -> auto& { return c.fusion.retire_views; }, 0, 255),
      Real("fusion.retire_fraction", "retirement: a piece leaves the published map when at least this "
           "share of its cells (0.5 m trimmed at each end) are seen through; it comes back when seen again",
           [](C& c) -> auto& { return c.fusion.retire_fraction; }, {0, 1, true}),
      Real("fusion.refit_tolerance_m", "bounded mode: a published wall whose refit moves neither endpoint "
           "by more than this keeps its geometry (only its counts are updated), sparing the "
           "re-consolidation and corner pass; metres, 0 = every refit re-resolves",
           [](C& c) -> auto& { return c.fusion.refit_tolerance_m; }, {0, 0.05}),
      Real("fusion.max_wall_length_m", "no wall is longer than this: a longer feature is refused and "
           "clusters do not grow past it (bounds the work one observation can cause), metres",
           [](C& c) -> auto& { return c.fusion.max_wall_length_m; }, {1, 1e6}),
      Count("fusion.max_component_nodes", "bounded mode: a link that would give a cluster the chain guard "
            "regroups more than this many representatives is not made; bounds the work one observation "
            "can cause (docs/reliability.md)",
            [](C& c) -> auto& { return c.fusion.max_component_nodes; }, 16, 1048576),
      Count("fusion.max_link_candidates", "bounded mode: earlier representatives one new feature is "
            "compared with at most (whole grid cells in a fixed order); bounds the work per feature",
            [](C& c) -> auto& { return c.fusion.max_link_candidates; }, 16, 1048576),
      Count("fusion.max_wall_pieces", "bounded mode: wall consolidation joins the pieces of a connected "
            "set of at most this many; those of a larger one stay walls of their own (bounds the work "
            "one observation can cause)",
            [](C& c) -> auto& { return c.fusion.max_wall_pieces; }, 16, 1048576),

      // Non-vertical planes (fusion/plane_engine.h, docs/fusion.md "Non-vertical planes").
      Real("planes.max_normal_angle_deg", "plane criterion 1: max angle between normals, degrees",
           [](C& c) -> auto& { return c.planes.max_normal_angle_rad; }, {0, 90, true}, kDegToRad),
      Real("planes.max_offset_m", "plane criterion 2: max distance of each boundary centroid to the other "
           "plane, metres",
           [](C& c) -> auto& { return c.planes.max_offset_m; }, {0, 100}),
      Real("planes.min_overlap", "plane criterion 3: min overlap of the projected boundaries as a share of "
           "the smaller one's area; 0 = touching or within planes.max_gap_m is enough",
           [](C& c) -> auto& { return c.planes.min_overlap; }, {0, 1}),
      Real("planes.max_gap_m", "plane criterion 3: max gap between the projected boundaries, metres",
           [](C& c) -> auto& { return c.planes.max_gap_m; }, {0, 100}),
      Count("planes.min_support", "observations a fused plane needs to be published",
            [](C& c) -> auto& { return c.planes.min_support; }, 1, 1000000),
      Real("planes.cover_m", "a plane within this of the boundary of a cluster seen by 32+ observations is "
           "folded into it, metres",
           [](C& c) -> auto& { return c.planes.cover_m; }, {0, 100}),

      Count("limits.max_features_per_batch", "lines + planes in one batch",
            [](C& c) -> auto& { return c.ingest.limits.max_features_per_batch; }, 1, kMaxFeaturesPerBatchHard),
      Count("limits.max_boundary_points", "boundary points of one plane",
            [](C& c) -> auto& { return c.ingest.limits.max_boundary_points; }, 3, 1000000),
      Real("limits.max_abs_coordinate_m", "a coordinate farther than this from the origin is refused as a unit "
           "or frame error, metres",
           [](C& c) -> auto& { return c.ingest.limits.max_abs_coordinate_m; }, {0, 1e6, true}),
      Real("limits.max_feature_length_m", "a line longer than this, or a plane whose boundary spans more, "
           "is refused; at most fusion.max_wall_length_m, metres",
           [](C& c) -> auto& { return c.ingest.limits.max_feature_length_m; }, {0, 1e6, true}),
      Real("limits.quaternion_tolerance", "accepted | |q| - 1 | of a pose quaternion or a plane normal",
           [](C& c) -> auto& { return c.ingest.limits.quaternion_tolerance; }, {0, 0.49, true}),
      Count("limits.max_in_flight", "unacknowledged batches per stream before reading pauses",
            [](C& c) -> auto& { return c.ingest.max_in_flight; }, 1, 1000000),
      Count("limits.max_message_bytes", "largest gRPC message accepted, bytes",
            [](C& c) -> auto& { return c.max_message_bytes; }, 1024, 1u << 30),
      Count("limits.max_group_batches", "batches committed in one transaction at most",
            [](C& c) -> auto& { return c.max_group_batches; }, 1, 1000000),
      Real("limits.fusion_share_after_s", "once this much fusion work (estimated fuser seconds) waits, "
           "a robot keeping more than limits.fusion_share_factor times the other robots' average "
           "waiting gets RESOURCE_EXHAUSTED for its batches (nothing stored), so the others keep "
           "being acknowledged; 0 = never",
           [](C& c) -> auto& { return c.fusion_share_after_s; }, {0, 3600}),
      Real("limits.fusion_share_factor", "how many times the other robots' average waiting fusion work "
           "one robot may keep waiting (see limits.fusion_share_after_s)",
           [](C& c) -> auto& { return c.fusion_share_factor; }, {1, 1000}),
      Count("limits.max_submap_bytes", "largest submap file UploadSubmap accepts, bytes",
            [](C& c) -> auto& { return c.submaps.max_submap_bytes; }, 64, uint64_t{1} << 34),
      Count("limits.max_concurrent_merges", "submap merges computed at once",
            [](C& c) -> auto& { return c.submaps.max_concurrent_merges; }, 1, 64),
      Count("limits.max_queued_merges", "merges waiting for a slot; beyond it MergeSubmaps answers "
            "RESOURCE_EXHAUSTED",
            [](C& c) -> auto& { return c.submaps.max_queued_merges; }, 0, 1024),
      Count("limits.max_submap_voxels", "occupied voxels one uploaded submap may expand to at the finest "
            "resolution, counted from the tree before anything is built (a merge holds ~100 bytes per voxel "
            "of its inputs)",
            [](C& c) -> auto& { return c.submaps.max_submap_voxels; }, 1, uint64_t{1} << 40),
      Count("limits.max_concurrent_uploads", "submap uploads received or stored at once; one more gets "
            "RESOURCE_EXHAUSTED at once; upload memory <= ~2 x this x limits.max_submap_bytes",
            [](C& c) -> auto& { return c.submaps.max_concurrent_uploads; }, 1, 1024),
      Real("limits.upload_idle_timeout_s", "an upload that sends nothing for this long is ended "
           "(DEADLINE_EXCEEDED), seconds",
           [](C& c) -> auto& { return c.submaps.upload_idle_timeout_s; }, {0, 86400, true}),
      Count("limits.max_streams", "Ingest and UploadSubmap streams open at once, server-wide (those relayed "
            "to another instance too); one more gets RESOURCE_EXHAUSTED at once",
            [](C& c) -> auto& { return c.streams.max_streams; }, 1, 10000000),
      Count("limits.max_streams_per_connection", "concurrent streams of one HTTP/2 connection "
            "(SETTINGS_MAX_CONCURRENT_STREAMS)",
            [](C& c) -> auto& { return c.streams.max_streams_per_connection; }, 1, 1000000),
      Real("limits.stream_opens_per_s", "streams a client address may open per second (token bucket; "
           "beyond it RESOURCE_EXHAUSTED), 1/s",
           [](C& c) -> auto& { return c.streams.stream_opens_per_s; }, {0, 1e9, true}),
      Real("limits.stream_open_burst", "streams a client address may open at once above that rate",
           [](C& c) -> auto& { return c.streams.stream_open_burst; }, {1, 1e9}),
      Real("limits.keepalive_time_s", "ping a connection after this long without traffic, seconds",
           [](C& c) -> auto& { return c.streams.keepalive_time_s; }, {1, 86400}),
      Real("limits.keepalive_timeout_s", "drop a connection whose ping is not answered within this, seconds",
           [](C& c) -> auto& { return c.streams.keepalive_timeout_s; }, {1, 3600}),
      Real("limits.min_client_ping_interval_s", "a client pinging more often than this is dropped, seconds",
           [](C& c) -> auto& { return c.streams.min_client_ping_interval_s; }, {0, 3600}),
      Real("limits.max_connection_idle_s", "close a connection that has had no stream for this long, "
           "seconds; 0 = never",
           [](C& c) -> auto& { return c.streams.max_connection_idle_s; }, {0, 1e7}),
      Real("limits.max_connection_age_s", "close any connection gracefully after this long (clients "
           "reconnect), seconds; 0 = never",
           [](C& c) -> auto& { return c.streams.max_connection_age_s; }, {0, 1e7}),
      Real("limits.read_wait_s", "GetFeatureMap waits at most this long for the fuser to reflect every "
           "acknowledged batch (unless the request asks for longer), then answers with the map as it is, "
           "seconds",
           [](C& c) -> auto& { return c.streams.read_wait_s; }, {0, 3600}),
      Real("limits.max_read_wait_s", "the longest wait a GetFeatureMap request may ask for (max_wait_ms), "
           "seconds",
           [](C& c) -> auto& { return c.streams.max_read_wait_s; }, {0, 3600}),
      Count("limits.watch_history", "changes of the fused map kept in memory for WatchFeatureMap clients "
            "that reconnect (one per fuser round); an older since_map_version gets a resync (the full map)",
            [](C& c) -> auto& { return c.watch.history; }, 0, 1000000),
      Count("limits.watch_queue", "changes queued per WatchFeatureMap stream; a slower reader is marked "
            "behind and gets a resync when it reads again (ingest never waits for it)",
            [](C& c) -> auto& { return c.watch.queue; }, 1, 1000000),
      Count("limits.max_watchers", "WatchFeatureMap streams open at once; one more gets RESOURCE_EXHAUSTED",
            [](C& c) -> auto& { return c.watch.max_watchers; }, 1, 100000),
      Count("limits.log_lines_per_s", "log lines per event and second; the rest is counted in one "
            "event=log_suppressed line",
            [](C& c) -> auto& { return c.streams.log_lines_per_s; }, 1, 1000000),
      Real("limits.audit_denials_per_minute", "audit rows of refused calls per identity (token or "
           "certificate) and minute, and as many at once; the rest are counted and written as one "
           "'N more denials of ACTION by WHO' row per action",
           [](C& c) -> auto& { return c.streams.audit_denials_per_minute; }, {1, 100000}),
      Count("limits.audit_max_denied_rows", "rows of refused calls kept in the audit log; older ones "
            "are deleted once a minute (rows of allowed actions are always kept)",
            [](C& c) -> auto& { return c.streams.audit_max_denied_rows; }, 100, 100000000),

      Count("http.port", "the web view (a page, JSON, server-sent events, /metrics) on this TCP port; "
            "0 = off. GETs follow the read rule, approving or rejecting merges needs an operator token "
            "when tokens are in use (docs/operations.md, \"Web view\")",
            [](C& c) -> auto& { return c.web.port; }, 0, 65535),
      Text("http.address", "address the web view listens on; off loopback also needs allow_insecure_remote "
           "(plain HTTP)", [](C& c) -> auto& { return c.web.address; }),

      Count("merge.min_matched_corners", "matched corners a pairwise merge needs to be accepted (a rigid "
            "transform needs 3)",
            [](C& c) -> auto& { return c.submaps.min_matched_corners; }, 3, 100000),
      Real("merge.max_residual_voxels", "largest accepted RMS residual after ICP, voxels of the coarser "
           "map of the pair",
           [](C& c) -> auto& { return c.submaps.max_residual_voxels; }, {0, 100, true}),
      Real("merge.min_overlap_score", "smallest accepted overlap score (0.7 let a 90-degree-wrong merge through)",
           [](C& c) -> auto& { return c.submaps.min_overlap_score; }, {0, 1}),
      Real("merge.min_shared_free_ratio", "free space both maps saw, per voxel where their surfaces "
           "coincide (B's free voxels on A's free space); a placement that only puts one map's wall on "
           "the other's shares none, right merges of real maps 2.6-12; only when both maps carry free "
           "space; 0 = off",
           [](C& c) -> auto& { return c.submaps.min_shared_free_ratio; }, {0, 1000}),
      Real("merge.max_restart_spread_voxels", "ICP restarted from the answer turned 1.5 deg about each "
           "axis may end at most this far from it at B's corners, voxels of the coarser map; further, "
           "the overlap does not fix the alignment and the pair is refused (every right merge of the "
           "real-map benchmark below it, a wrong one at 10 % overlap 7.3); 0 = off",
           [](C& c) -> auto& { return c.submaps.max_restart_spread_voxels; }, {0, 1000}),
      Real("merge.max_seconds", "time budget of one merge, seconds",
           [](C& c) -> auto& { return c.submaps.max_merge_seconds; }, {0, 86400, true}),
      Count("merge.threads", "threads one merge uses (0: the machine's cores); "
            "limits.max_concurrent_merges merges run at once and the rest queue, so the cores are "
            "not oversubscribed",
            [](C& c) -> auto& { return c.submaps.merge_threads; }, 0, 256),
      Count("merge.prepared_submaps_mib", "memory for uploads read and levelled ahead of their "
            "merges, in a free merge slot, and kept for the next merges of them (a 150k-voxel "
            "campus crop takes 60-100 MiB and spares each of its merges ~0.5 s); least recently "
            "used first out; 0 = none: every merge reads its inputs",
            [](C& c) -> auto& { return c.submaps.prepared_submaps_mib; }, 0, 1 << 20),
      Choice("merge.resolution_policy", "submaps of different resolutions: refuse, or resample to the finest",
             [](C& c) -> auto& { return c.submaps.resample_resolutions; }, "refuse", "resample"),
      Choice("merge.fusion_rule", "occupancy fusion: overlap (the paper's rule) or log_odds",
             [](C& c) -> auto& { return c.submaps.log_odds_fusion; }, "overlap", "log_odds"),
      Flag("merge.correlation", "use the correlation generator (levelled maps, wall-normal yaws, FFT "
           "translation search with a free-space penalty) besides corner matching; false = corner matching "
           "only (the paper)",
           [](C& c) -> auto& { return c.submaps.correlation; }),
      Count("merge.correlation_after_corner_stages", "the correlation generator runs after this many corner-"
            "matching tolerance stages (strict, then looser) accepted nothing; 0 = before corner matching (corners "
            "only when it accepts nothing: same outcomes on the benchmark, 30-45 % less CPU indoors), 1 = after "
            "the strict stage, 3 = after all of them",
            [](C& c) -> auto& { return c.submaps.correlation_after_corner_stages; }, 0, 100),
      Count("merge.correlation_max_cells", "cells of the correlation generator's FFT grid (~40 bytes each, "
            "per running merge); a map too large for cells of 3 voxels gets coarser ones, and outdoors those "
            "place fewer maps (campus maps 71-132 m across at 0.2 m need 11.5-16M cells)",
            [](C& c) -> auto& { return c.submaps.correlation_max_cells; }, 1000, 200'000'000),
      Count("merge.correlation_plan_view_first_cells", "pairs whose correlation grid would exceed this many "
            "cells (outdoor maps; indoor submaps need 0.9-1.9M) are placed by the plan view first, and the 3D "
            "search runs at an accepted placement's yaw and its 180 deg twin alone (campus merges at 20-50 % "
            "overlap: a third less CPU); 0 = every pair, 200000000 = never",
            [](C& c) -> auto& { return c.submaps.correlation_plan_view_first_cells; }, 0, 200'000'000),
      Flag("merge.correlation_check_accepted", "when corner matching goes first "
           "(merge.correlation_after_corner_stages >= 1): also run the correlation generator after an accepted "
           "corner solution, so that the uniqueness gate sees the other yaws (on geb079 0.6-0.8 s of the "
           "1.9-2.5 s of CPU of an accepted merge)",
           [](C& c) -> auto& { return c.submaps.correlation_check_accepted; }),
      Flag("merge.correlation_looser_stages", "also run corner matching's looser tolerance stages after the "
           "correlation generator searched and accepted nothing (they always run when it cannot run); on the "
           "benchmark they placed no further map and were half of a refusal's CPU",
           [](C& c) -> auto& { return c.submaps.correlation_looser_stages_after_refusal; }),
      Flag("merge.review", "every merge the gates accept waits for an operator's ApproveMerge (stored "
           "PROPOSED: no frame tied, global map unchanged), as if each request set review",
           [](C& c) -> auto& { return c.submaps.merge_review; }),
  };
  // clang-format on
  return kSettings;
}

}  // namespace mapd::service
