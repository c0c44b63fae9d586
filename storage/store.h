// The map server's persistence: one SQLite database file in WAL mode.
//
// Writes go through ONE connection, used by one thread (mapd's writer), in
// group transactions: SQLite 3.40's WAL-reset race needs two concurrent
// writers, and a single writer also lets many robots' batches share a commit.
// Reads (queries, restart) use a second connection of their own.
//
// Thread safety: BeginWrite(), WriteTransaction and Checkpoint() belong to the
// writer thread. The read methods may be called from any thread; they are
// serialised on the reader connection.
#ifndef MAPD_STORAGE_STORE_H_
#define MAPD_STORAGE_STORE_H_

#include <Eigen/Core>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <string_view>
#include <unordered_map>
#include <vector>

#include "common/status.h"
#include "geometry/observation.h"
#include "geometry/rigid3.h"
#include "geometry/segment2.h"
#include "storage/sqlite.h"

namespace mapd::storage {

struct StoreOptions {
  // false: synchronous=NORMAL, a commit survives a crash of mapd but maybe not
  // of the machine. true: synchronous=FULL, it survives power loss too.
  bool synchronous_full = false;
  // How long a write waits for a lock held by another process (e.g. a backup
  // or an operator's sqlite3 shell) before it fails, milliseconds.
  int busy_timeout_ms = 5000;
  // The database file grows to this at most (PRAGMA max_page_count); beyond
  // it writes fail as on a full disk (ResourceExhausted). 0 = no limit, bytes.
  uint64_t max_db_bytes = 0;
};

enum class FrameKind : int {
  kMap = 1,    // the session's poses are in the map frame
  kLocal = 2,  // the session has its own frame, tied later by a submap merge
};

// A robot session's frame and how it relates to the map frame.
struct SessionFrame {
  int64_t session_id = 0;
  int64_t robot_id = 0;
  FrameKind kind = FrameKind::kMap;
  bool tied = false;             // T_map_frame is known
  geometry::Rigid3 T_map_frame;  // valid when tied
  // Where the tie happened in the commit order (0, 0: tied from the start):
  // the newest observation id committed before it, and the tying
  // transaction's sequence number (1, 2, ...).
  int64_t tied_through_observation = 0;
  int64_t tie_seq = 0;
};

// A stored snapshot of the fusion state (MapCore): it reflects every tied
// observation with id <= through_observation and every tie with tie_seq <=
// through_tie_seq.
struct FusionSnapshot {
  int64_t id = 0;
  int64_t created_ns = 0;
  uint64_t map_version = 0;
  int64_t through_observation = 0;
  int64_t through_tie_seq = 0;
  std::string params;  // the fusion parameters it was built with
  std::string state;   // FusionEngine::SaveState()
  // PlaneFusionEngine::SaveState(); has_plane_state is false for snapshots
  // taken before plane fusion (schema version 5), which are then not used.
  std::string plane_state;
  bool has_plane_state = false;
};

// A snapshot written in parts: its bytes (state, then plane_state) in `count`
// parts named by `key`, each stored in a transaction of its own
// (WriteTransaction::InsertSnapshotPart), so that no commit holds the
// database for long; the snapshot exists once its row is stored
// (WriteTransaction::InsertSnapshot with these parts).
struct SnapshotParts {
  int64_t key = 0;  // unique per snapshot
  int count = 0;    // 0: the bytes are in the row itself
};

// `snapshot`'s bytes cut into the parts InsertSnapshot expects: state, then
// plane_state, in slices of at most `part_bytes` (> 0); views into `snapshot`.
std::vector<std::string_view> SnapshotPartsOf(const FusionSnapshot& snapshot, size_t part_bytes);

// One batch to store.
struct NewObservation {
  std::string robot;
  std::string session;
  uint64_t seq = 0;
  int64_t stamp_ns = 0;
  int64_t received_ns = 0;
  FrameKind frame_kind = FrameKind::kMap;
  const geometry::SensorObservation* features = nullptr;  // pose + lines + planes, sensor frame
};

struct InsertResult {
  bool stored = false;         // false: (robot, session, seq) was stored before
  int64_t observation_id = 0;  // the row id (of the earlier row for a duplicate)
  SessionFrame frame;
};

// A stored observation, as read back.
struct StoredObservation {
  int64_t id = 0;
  int64_t robot_id = 0;
  int64_t session_id = 0;
  uint64_t seq = 0;
  int64_t stamp_ns = 0;
  geometry::SensorObservation features;
};

// A row of the published fused map.
struct FusedRow {
  uint64_t id = 0;
  int kind = 1;  // 1 = line, 2 = plane (mapserver.v1.FeatureKind)
  geometry::Segment2 segment;
  double z_min_m = 0, z_max_m = 0;
  uint32_t support = 0;
  uint32_t member_count = 0;
  std::string robots;  // comma-separated robot names
};

// A row of the published fused non-vertical planes (fusion/plane_engine.h).
struct FusedPlaneRow {
  uint64_t id = 0;
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();  // unit, map frame
  double offset_m = 0;
  std::vector<Eigen::Vector3d> boundary;  // map frame, counter-clockwise about normal
  double area_m2 = 0;
  double z_min_m = 0, z_max_m = 0;
  uint32_t support = 0;
  uint32_t member_count = 0;
  std::string robots;  // comma-separated robot names
};

struct StampedPose {
  uint64_t seq = 0;
  int64_t stamp_ns = 0;
  geometry::Rigid3 T_frame_sensor;
};

struct RobotSummary {
  int64_t id = 0;
  std::string name;
  int64_t first_seen_ns = 0;
  int64_t last_seen_ns = 0;
  uint64_t batches = 0;
  uint64_t features = 0;
  uint32_t sessions = 0;
  bool all_sessions_tied = false;
};

// One robot session's sensor positions (Store::ListTrails), session frame.
struct TrailPoint {
  uint64_t seq = 0;
  int64_t stamp_ns = 0;
  Eigen::Vector3d position = Eigen::Vector3d::Zero();  // T_frame_sensor's translation
};
struct SessionTrailRows {
  std::string robot;
  std::string session;
  int64_t session_id = 0;
  uint64_t stored = 0;             // observations stored for the session, before thinning
  std::vector<TrailPoint> points;  // by seq
};

// --- Voxel submaps and merges.

// Robot name under which merged maps are stored. '@' is outside the API's
// robot_id alphabet ([A-Za-z0-9_.-]), so no real robot can collide with it,
// and ListRobots / Counts leave such rows out.
inline constexpr char kMergedRobot[] = "@merged";

enum class SubmapFormat : int { kOctomapBt = 1, kOctomapOt = 2 };  // = mapserver.v1.SubmapFormat

// What is stored about a submap besides its bytes.
struct SubmapMeta {
  int64_t id = 0;
  std::string robot;
  std::string name;
  int64_t session_id = 0;  // 0 = built in no known session frame
  SubmapFormat format = SubmapFormat::kOctomapBt;
  double resolution_m = 0;
  uint64_t occupied_voxels = 0;
  uint64_t free_voxels = 0;
  Eigen::Vector3d bounds_min = Eigen::Vector3d::Zero();  // metres, submap frame
  Eigen::Vector3d bounds_max = Eigen::Vector3d::Zero();
  int64_t created_ns = 0;
  uint64_t size_bytes = 0;
};

// Where an accepted merge placed a submap in the map frame.
struct SubmapPlacement {
  int64_t submap_id = 0;
  int64_t merge_id = 0;
  geometry::Rigid3 T_map_submap;
};

// One submap of the global map and the pose it was fused at.
struct GlobalMapMember {
  int64_t submap_id = 0;
  geometry::Rigid3 T_map_submap;
};

// The global map as built last (service/global_map_builder.h): the union, in
// the map frame, of `members` fused in that order.
struct GlobalMapRecord {
  uint64_t version = 0;  // 1, 2, ... one per change
  int64_t built_ns = 0;
  double resolution_m = 0;
  uint64_t occupied_voxels = 0;
  uint64_t free_voxels = 0;
  std::vector<GlobalMapMember> members;
  std::string data;  // .bt; empty when read without it
};

struct NewSubmap {
  SubmapMeta meta;        // id, session_id and size_bytes are filled in by the store
  std::string session;    // the robot's session the map is built in; empty = none
  std::string_view data;  // the validated file; must outlive InsertSubmap()
};

// A matched corner pair of a merge input (voxel::MatchedCorner), metres.
struct MatchedCornerRecord {
  Eigen::Vector3d in_submap = Eigen::Vector3d::Zero();
  Eigen::Vector3d in_reference = Eigen::Vector3d::Zero();
};

// One input of a merge as recorded. For a refused merge only submap_id is meaningful.
struct MergeInputRecord {
  int64_t submap_id = 0;
  bool aligned = false;                 // the transform and scores below are set
  geometry::Rigid3 T_reference_submap;  // maps the submap into the first input's frame
  int matched_corners = 0;
  double residual_m = 0;
  double overlap_score = 0;
  // The corner pairs behind matched_corners (empty for the first input, and
  // for merges recorded before schema 7).
  std::vector<MatchedCornerRecord> matched;
  // The rest of the placing edge's gate figures (voxel::Alignment): its
  // generator ("" when unknown), support fraction, shared free ratio, restart
  // spread (voxels of the coarser map) and the runner-up's residual (metres);
  // -1 where not measured, and for merges recorded before schema 8.
  std::string source;
  double support_fraction = -1;
  double shared_free_ratio = -1;
  double restart_spread_voxels = -1;
  double second_residual_m = -1;
};

// = mapserver.v1.MergeState. Stored as text ('proposed', ...; MergeStateName).
enum class MergeState : int { kProposed = 1, kAccepted = 2, kRejected = 3, kRefused = 4 };
const char* MergeStateName(MergeState state);  // "proposed", "accepted", ...

struct MergeRecord {
  int64_t id = 0;
  int64_t created_ns = 0;
  MergeState state = MergeState::kRefused;
  std::string reason;            // refused: the gates' reason; rejected: the operator's
  int64_t merged_submap_id = 0;  // 0 when refused
  std::vector<MergeInputRecord> inputs;
  std::string requested_by;  // who asked for it (empty in databases before schema 6)
  std::string decided_by;    // who approved or rejected it (accepted at once: requested_by)
  int64_t decided_ns = 0;    // 0 while proposed and when refused
};

struct NewMerge {
  MergeRecord record;  // id and merged_submap_id are filled in by the store
  NewSubmap merged;    // accepted merges only: the merged map, stored as a submap
};

struct MergeIds {
  int64_t merge_id = 0;
  int64_t merged_submap_id = 0;
};

struct StoreCounts {
  uint64_t robots = 0, sessions = 0, observations = 0, raw_features = 0, fused = 0, submaps = 0;
};

// --- Identities and the audit log (storage/auth_store.cc).

// A token as stored: never its secret, only the secret's SHA-256.
struct TokenRecord {
  int64_t id = 0;
  std::string name;           // unique, chosen by whoever created it
  std::string role;           // reader / robot / operator / admin (server/service/auth.h)
  std::string robot_id;       // robot tokens: the robot they write for
  std::string secret_sha256;  // 32 bytes
  int64_t created_ns = 0;
  std::string created_by;  // the creator's name ("mapd token create" offline)
  int64_t revoked_ns = 0;  // 0 while valid
  std::string maps;        // the maps it may act on, comma-separated; empty = every map
};

struct AuditEntry {
  int64_t id = 0;
  int64_t time_ns = 0;
  std::string who;  // token name or certificate CN
  std::string role;
  std::string action;      // the RPC, e.g. "UploadSubmap"
  std::string target;      // what it acted on, e.g. "robot r1 submap 'room'"
  std::string result;      // "ok", "denied: ...", or the error
  std::string peer;        // the caller's address as gRPC or HTTP gives it ('' offline)
  std::string credential;  // "token", "certificate", "none" (open mode), "database file"
};

class Store;

// A group of writes committed together. Rolls back unless Commit() succeeds.
class WriteTransaction {
 public:
  ~WriteTransaction();
  WriteTransaction(const WriteTransaction&) = delete;
  WriteTransaction& operator=(const WriteTransaction&) = delete;

  // Inserts one batch unless (robot, session, seq) is stored already. Creates
  // the robot and session on first sight. A batch whose frame kind disagrees
  // with its session's is refused with InvalidArgument; the transaction goes on.
  StatusOr<InsertResult> InsertObservation(const NewObservation& obs);
  Status UpsertFused(const FusedRow& row);

  // Stores a validated submap. AlreadyExists when the robot has a submap of
  // that name; FailedPrecondition when `session` is given but unknown (the
  // robot must have streamed a batch in it). Creates the robot on first sight.
  StatusOr<int64_t> InsertSubmap(const NewSubmap& submap);
  // NotFound when there is no such submap. FailedPrecondition when an accepted
  // merge used it as an input or produced it: the merge record and the session
  // frames it tied derive from those bytes, so they stay. Refused merges do
  // not pin their inputs.
  Status DeleteSubmap(int64_t id);
  // Records a merge. An accepted or proposed one also stores `merged` as a
  // submap of robot kMergedRobot named "merge-<merge id>".
  StatusOr<MergeIds> RecordMerge(const NewMerge& merge);
  // Ends a proposed merge: kAccepted or kRejected, by `who` at `now_ns`
  // (`reason` for a rejection). NotFound if there is no such merge,
  // FailedPrecondition naming its state if it is not proposed. Ties nothing:
  // the caller ties the sessions in the same transaction.
  Status DecideMerge(int64_t id, MergeState state, const std::string& who, int64_t now_ns,
                     const std::string& reason);
  // Records where an accepted merge placed a submap in the map frame; a
  // submap placed before keeps its first placement (as a tie is never moved).
  Status PlaceSubmap(int64_t submap_id, int64_t merge_id, const geometry::Rigid3& T_map_submap);
  // Replaces the global map (global_map_store.cc); DeleteGlobalMap removes it
  // (no member left).
  Status PutGlobalMap(const GlobalMapRecord& map);
  Status DeleteGlobalMap();
  // Ties a session frame to the map frame (T_map_frame). FailedPrecondition
  // if it is tied already: a tie is never moved, so the map stays consistent.
  // The tie is recorded at set_tie_point()'s position in the commit order.
  Status TieSession(int64_t session_id, const geometry::Rigid3& T_map_frame);
  // The newest observation id committed before this transaction (MapCore sets
  // it before running a write that may tie sessions).
  void set_tie_point(int64_t newest_observation_id) { tie_point_ = newest_observation_id; }
  // Raw retention: deletes up to `limit` of the oldest observations received
  // before `received_before_ns` that every stored snapshot reflects (never
  // one of a session not tied, or tied after a snapshot, and never the newest
  // observation), then returns the freed pages to the file system (new
  // databases; see Store::Open). Returns how many were deleted.
  StatusOr<uint64_t> DropRawObservations(int64_t received_before_ns, int limit);
  // Stores a snapshot and deletes the rows of all but the `keep` newest (their
  // parts stay until DeleteUnusedSnapshotParts). With parts.count > 0, the
  // bytes are the parts stored before under parts.key, and only the sizes of
  // state and plane_state are taken from `snapshot`.
  Status InsertSnapshot(const FusionSnapshot& snapshot, int keep, SnapshotParts parts = {});
  // Part `index` (0, 1, ...) of the snapshot that will name `key`.
  Status InsertSnapshotPart(int64_t key, int index, std::string_view bytes);
  // Deletes up to `limit` parts that no stored snapshot names (a pruned
  // snapshot's, or those of one a stop or crash interrupted); returns how many.
  // Not while a snapshot's parts are being written: they are not named yet.
  StatusOr<int> DeleteUnusedSnapshotParts(int limit);
  // True once TieSession() succeeded in this transaction.
  bool ties_sessions() const { return !new_ties_.empty(); }
  // The sequence number of this transaction's ties (0 if it tied none).
  int64_t tie_seq() const { return tie_seq_; }
  // The sessions TieSession() tied in this transaction, ascending.
  std::vector<int64_t> tied_session_ids() const;
  Status DeleteFused(uint64_t id);
  // Fused planes (storage/plane_store.cc).
  Status UpsertFusedPlane(const FusedPlaneRow& row);
  Status DeleteFusedPlane(uint64_t id);
  // Stores a new token (id filled in by the store); AlreadyExists for a taken name.
  StatusOr<int64_t> InsertToken(const TokenRecord& token);
  // Marks a token revoked; NotFound if there is none, FailedPrecondition if
  // it is revoked already.
  Status RevokeToken(int64_t id, int64_t now_ns);
  // Control characters in `entry`'s fields are stored escaped (one line each).
  Status AppendAudit(const AuditEntry& entry);
  // Deletes the oldest rows of refused calls (result "denied...") beyond the
  // newest `keep`; returns how many. Other rows are never deleted.
  StatusOr<int64_t> TrimDeniedAudit(int64_t keep);
  // Durable once this returns OK (per StoreOptions::synchronous_full).
  Status Commit();

 private:
  friend class Store;
  explicit WriteTransaction(Store* store) : store_(store) {}
  struct RobotDelta {
    uint64_t batches = 0, features = 0;
    int64_t last_seen_ns = 0;
  };
  StatusOr<int64_t> RobotId(const std::string& name, int64_t now_ns);
  StatusOr<SessionFrame> Session(int64_t robot_id, const std::string& name, FrameKind kind,
                                 int64_t now_ns);

  Store* store_;
  bool open_ = true;
  std::unordered_map<std::string, int64_t> new_robots_;
  std::unordered_map<std::string, SessionFrame> new_sessions_;  // key: robot_id/name
  std::unordered_map<int64_t, RobotDelta> robot_deltas_;
  std::unordered_map<int64_t, geometry::Rigid3> new_ties_;  // session id -> T_map_frame
  int64_t tie_point_ = 0;
  int64_t tie_seq_ = 0;  // of this transaction's ties, once one is made
  std::string payload_;  // scratch
};

class Store {
 public:
  // Opens the database at `path`, creating it owner-only (mode 0600) when it
  // does not exist, and migrates its schema.
  static StatusOr<std::unique_ptr<Store>> Open(const std::string& path,
                                               const StoreOptions& options);
  ~Store();

  // --- Writer thread only.
  StatusOr<std::unique_ptr<WriteTransaction>> BeginWrite();
  // Copies the WAL into the database file and truncates it (shutdown, idle).
  Status Checkpoint();
  // Whether the database takes writes now, after a write failed: its file
  // system has kProbeFreeBytes free, and 1 MiB commits (then is deleted).
  // So a full disk is not declared writable again on its last blocks.
  Status ProbeWrite();
  static constexpr uint64_t kProbeFreeBytes = uint64_t{8} << 20;

  // --- Any thread.
  // Every stored observation in id (= arrival) order.
  Status ForEachObservation(const std::function<Status(const StoredObservation&)>& fn);
  // The stored observations with after_id < id <= through_id, in id order,
  // read in pages: `fn` runs without the reader lock (other reads go on), and
  // rows committed meanwhile past a page are seen (ids only grow).
  Status ForEachObservationBetween(int64_t after_id, int64_t through_id,
                                   const std::function<Status(const StoredObservation&)>& fn);
  // The newest stored observation id (0 if none).
  StatusOr<int64_t> NewestObservationId();
  // The newest snapshot (skip = 1: the one before it), its parts put back
  // together; NotFound if none, Internal if its parts are not all there.
  StatusOr<FusionSnapshot> LatestSnapshot(int skip = 0);
  // The stored observations of `session_ids` with id <= max_id, in id order.
  Status ForEachObservationOfSessions(const std::vector<int64_t>& session_ids, int64_t max_id,
                                      const std::function<Status(const StoredObservation&)>& fn);
  StatusOr<std::vector<SessionFrame>> ListSessions();
  // A committed session by id, or by robot and session name (from the cache).
  StatusOr<SessionFrame> GetSession(int64_t session_id) const;
  StatusOr<SessionFrame> FindSession(const std::string& robot, const std::string& session) const;

  // Submaps, by id; `robot` empty = all robots (merged maps included).
  StatusOr<std::vector<SubmapMeta>> ListSubmaps(const std::string& robot);
  StatusOr<SubmapMeta> GetSubmap(int64_t id);       // NotFound
  StatusOr<std::string> GetSubmapData(int64_t id);  // the stored file; NotFound
  // The global map as built last, with its bytes when `with_data`; NotFound
  // before one was built (global_map_store.cc).
  StatusOr<GlobalMapRecord> GetGlobalMap(bool with_data);
  // Every submap placement, by submap id.
  StatusOr<std::vector<SubmapPlacement>> ListPlacements();
  StatusOr<MergeRecord> GetMerge(int64_t id);       // NotFound
  StatusOr<std::vector<MergeRecord>> ListMerges();  // by id
  StatusOr<std::vector<FusedRow>> LoadFused();
  StatusOr<std::vector<FusedPlaneRow>> LoadFusedPlanes();  // by id
  StatusOr<std::vector<RobotSummary>> ListRobots();
  // The sensor poses of a session's newest `limit` observations, newest
  // first, in the session's frame (pose_store.cc; one index range read).
  StatusOr<std::vector<StampedPose>> RecentPoses(int64_t session_id, int limit);
  // Every session's stored sensor positions (of `robot`, or of all robots if
  // empty), by robot and session name; a session with more than
  // `max_points` (>= 2) observations is thinned evenly, first and last kept.
  StatusOr<std::vector<SessionTrailRows>> ListTrails(const std::string& robot, uint32_t max_points);
  StatusOr<StoreCounts> Counts();
  // Tokens: by id (NotFound), all of them by id, and whether any was ever made.
  StatusOr<TokenRecord> GetToken(int64_t id);
  StatusOr<std::vector<TokenRecord>> ListTokens();
  StatusOr<bool> AnyTokenEver();
  // The newest `limit` audit entries, newest first.
  StatusOr<std::vector<AuditEntry>> ListAudit(int limit);
  // Robot name by id, from the cache (empty if unknown).
  std::string RobotName(int64_t robot_id) const;
  // Database file plus WAL, bytes.
  uint64_t SizeBytes() const;
  const std::string& path() const { return path_; }

 private:
  friend class WriteTransaction;
  Store() = default;
  Status Prepare();
  // The observations with after_id < id <= through_id meeting the SQL
  // `condition` on o (observations) and s (sessions), in id order, read in
  // pages (see store.cc).
  Status ForEachObservationWhere(const std::string& condition, int64_t after_id, int64_t through_id,
                                 const std::function<Status(const StoredObservation&)>& fn);
  static std::string SessionKey(int64_t robot_id, const std::string& name) {
    return std::to_string(robot_id) + "/" + name;
  }

  std::string path_;
  DbHandle writer_;
  DbHandle reader_;
  std::mutex reader_mu_;  // guards reader_ and its statements

  // Writer statements.
  Statement begin_, commit_, rollback_;
  Statement insert_robot_, insert_session_, insert_obs_, find_obs_, update_robot_;
  Statement upsert_fused_, delete_fused_;

  // Committed robots and sessions (writer thread; names also read by RobotName).
  mutable std::mutex cache_mu_;
  std::unordered_map<std::string, int64_t> robot_ids_;
  std::unordered_map<int64_t, std::string> robot_names_;
  std::unordered_map<std::string, SessionFrame> sessions_;
  int64_t max_tie_seq_ = 0;  // GUARDED_BY(cache_mu_)
};

}  // namespace mapd::storage

#endif  // MAPD_STORAGE_STORE_H_
