// The plain option structs of mapd's parts (ingest, streams, submaps), kept
// apart from the code that uses them so that the configuration (config.h)
// is a leaf: it depends on these and on the algorithm parameters, nothing else.
// Defaults are the member initialisers here; ranges are checked by the
// settings table (config_settings.cc) and the Validate() methods.
#ifndef MAPD_SERVICE_OPTIONS_H_
#define MAPD_SERVICE_OPTIONS_H_

#include <cstddef>
#include <cstdint>
#include <string>

#include "common/status.h"

namespace mapd::service {

// Limits on one batch. Over-limit batches are refused with RESOURCE_EXHAUSTED.
struct IngestLimits {
  uint32_t max_features_per_batch = 1024;  // lines + planes; at most kFeatureIdBits allow
  uint32_t max_boundary_points = 1024;     // per plane
  double max_abs_coordinate_m = 1e6;       // anything farther is a unit or frame error
  // A line longer than this, or a plane whose boundary spans more (bounding
  // box diagonal), is refused: no wall is that long, and the fuser's work
  // grows with a feature's length (at most fusion.max_wall_length_m).
  double max_feature_length_m = 1000.0;
  double quaternion_tolerance = 1e-3;  // accepted | |q| - 1 |
  uint32_t max_id_length = 128;        // robot_id, session_id

  Status Validate() const;
};

// Raw feature ids are (observation id << kFeatureIdBits) | index in the batch.
constexpr int kFeatureIdBits = 12;
constexpr uint32_t kMaxFeaturesPerBatchHard = 1u << kFeatureIdBits;

struct IngestOptions {
  IngestLimits limits;
  uint32_t max_in_flight = 1024;  // per stream
  // The map the streams write (MapServiceImpl sets it from its placement;
  // not a setting): a batch naming another map is refused.
  std::string map_id = "default";
};

// Limits on connections and streams (floods, slow or idle clients).
struct StreamLimits {
  // Long-lived streams (Ingest, UploadSubmap) open at once, server-wide;
  // beyond it a new one is answered RESOURCE_EXHAUSTED at once.
  size_t max_streams = 2000;
  uint32_t max_streams_per_connection = 100;  // HTTP/2 SETTINGS_MAX_CONCURRENT_STREAMS
  // Token bucket per client address (host, port ignored): stream opens per
  // second, and the burst allowed above that rate.
  double stream_opens_per_s = 200.0;
  double stream_open_burst = 400.0;
  double keepalive_time_s = 60.0;     // ping an idle connection this often
  double keepalive_timeout_s = 20.0;  // ... and drop it when the ping is not answered within this
  // Clients pinging more often are dropped (ping flood). Robots ping every
  // 5 s while streaming (robot::RobotChannelArguments), to notice a frozen
  // server in seconds.
  double min_client_ping_interval_s = 5.0;
  double max_connection_idle_s = 600.0;  // close connections without streams after this; 0 = never
  double max_connection_age_s = 0.0;     // close any connection after this (gracefully); 0 = never
  // A read (GetFeatureMap) waits at most this long for the fuser to reflect
  // every acknowledged batch, unless the request asks for longer; then it
  // answers with the map as it is (map_version and fusion_pending say how old).
  double read_wait_s = 0.2;
  double max_read_wait_s = 30.0;  // the longest wait a request may ask for
  uint32_t log_lines_per_s = 20;  // per event; the rest is counted in one `log_suppressed` line
  // Audit rows of refused calls per identity and minute (and as many at
  // once); the rest are counted in summary rows (denial_audit.h).
  double audit_denials_per_minute = 10;
  // Denial rows kept in the database; older ones are deleted once a minute.
  // Allowed actions' rows are never deleted.
  uint32_t audit_max_denied_rows = 100000;
};

// The change feed (WatchFeatureMap, watch_hub.h). Memory: at most
// history + max_watchers x queue changes (each the changed features only).
struct WatchOptions {
  // Changes kept for resuming watches (one per round of the fuser, however
  // many observations it fused); older since_map_versions get a resync.
  size_t history = 1024;
  // Changes queued per watcher; a watcher further behind is marked behind and
  // gets a resync (the full filtered map) once it reads again.
  size_t queue = 256;
  size_t max_watchers = 64;  // one more watch is RESOURCE_EXHAUSTED at once
};

// The web view (server/web): an HTTP port, off unless port is set.
struct WebOptions {
  int port = 0;  // 0: off
  std::string address = "127.0.0.1";
};

// Voxel submaps and merges. The merge thresholds are voxel::MergeParams's
// (server/voxel/merge.h); they live here as plain values so that the config
// builds without the voxel library (MAPD_WITH_VOXEL=OFF).
struct SubmapOptions {
  size_t max_submap_bytes = size_t{64} << 20;  // one uploaded file at most, bytes
  // The map the uploads go to (MapServiceImpl sets it; not a setting): a
  // header naming another map is refused.
  std::string map_id = "default";
  size_t max_concurrent_merges = 1;  // merges computed at once
  // Merges waiting for a slot at most; one more is refused with
  // RESOURCE_EXHAUSTED (the caller retries later) rather than queued unbounded.
  size_t max_queued_merges = 4;
  int min_matched_corners = 4;  // evidence to accept a pairwise merge
  double max_residual_voxels =
      0.75;  // RMS after ICP, voxels of the coarser map (= voxel::MergeParams)
  double min_overlap_score =
      0.9;  // [0, 1] (= voxel::MergeParams; 0.7 let a 90-degree-wrong merge through)
  // B's free voxels on A's free space per coinciding voxel, when both maps
  // carry free space (= voxel::MergeParams; 0 = off): a placement that only
  // puts one map's wall on the other's shares none.
  double min_shared_free_ratio = 1.0;
  // Restarts of ICP turned 1.5 deg about each axis may end at most this far
  // from the answer at B's corners, voxels of the coarser map (=
  // voxel::MergeParams; 0 = off): further, the overlap does not fix the
  // alignment.
  double max_restart_spread_voxels = 4.0;
  double max_merge_seconds = 60.0;  // budget of one merge, seconds
  // Threads one merge uses (voxel::MergeParams::threads); 0: the machine's
  // cores. max_concurrent_merges merges run at once, the rest queue.
  size_t merge_threads = 0;
  // Memory for submaps read and viewed ahead of their merges (MiB; 0: none,
  // every merge reads its inputs). Uploads are prepared in a free merge slot.
  size_t prepared_submaps_mib = 512;
  bool resample_resolutions = false;  // false: different resolutions are refused
  bool log_odds_fusion = false;       // false: the paper's overlap rule
  // The correlation generator (voxel::CorrelationParams): run after the
  // first correlation_after_corner_stages corner-matching stages accepted
  // nothing (0: first, corner matching only when it accepts nothing), and,
  // when corner matching went first, also after an accepted solution so that
  // the uniqueness gate sees other yaws (correlation_check_accepted). CPU:
  // docs/voxel-merge.md.
  bool correlation = true;
  int correlation_after_corner_stages = 0;
  bool correlation_check_accepted = true;
  // Corner matching's looser stages after the generator searched and refused
  // (voxel::CorrelationParams::looser_stages_after_refusal).
  bool correlation_looser_stages_after_refusal = false;
  // Cap on its FFT grid (voxel::CorrelationParams::max_cells; ~40 bytes a cell).
  size_t correlation_max_cells = 16'000'000;
  // Pairs whose grid would exceed this are placed by the plan view first
  // (voxel::CorrelationParams::plan_view_first_min_cells; 0 = every pair).
  size_t correlation_plan_view_first_cells = 6'000'000;
  // Every merge the gates accept waits for ApproveMerge (PROPOSED), as if
  // each request set MergeSubmapsRequest.review.
  bool merge_review = false;
  // Occupied voxels one uploaded submap may expand to at the finest
  // resolution (counted from the tree structure before anything is built).
  uint64_t max_submap_voxels = 8'000'000;
  // Uploads being received or stored at once; one more is refused with
  // RESOURCE_EXHAUSTED at once. Upload memory <= about 2 x this x
  // max_submap_bytes.
  size_t max_concurrent_uploads = 2;
  double upload_idle_timeout_s = 30.0;  // an upload that sends nothing this long is ended
};

}  // namespace mapd::service

#endif  // MAPD_SERVICE_OPTIONS_H_
