// storage::Store on one SQLite database file in WAL mode: the embedded
// default, one file per map.
//
// Writes go through ONE connection, used by one thread (mapd's writer), in
// group transactions: SQLite 3.40's WAL-reset race needs two concurrent
// writers, and a single writer also lets many robots' batches share a commit.
// Reads (queries, restart) use a second connection of their own, serialised
// on a mutex.
//
// The methods are spread over files by intent: observations and sessions
// (store.cc), tokens and audit (auth_store.cc), fused planes
// (plane_store.cc), placements and the global map (global_map_store.cc),
// recent poses (pose_store.cc) and trails (trail_store.cc).
#ifndef MAPD_STORAGE_SQLITE_STORE_H_
#define MAPD_STORAGE_SQLITE_STORE_H_

#include <cstdint>
#include <memory>
#include <mutex>
#include <string>
#include <unordered_map>
#include <vector>

#include "storage/sqlite/sqlite.h"
#include "storage/store.h"

namespace mapd::storage {

class SqliteStore;

class SqliteWriteTransaction final : public WriteTransaction {
 public:
  ~SqliteWriteTransaction() override;
  SqliteWriteTransaction(const SqliteWriteTransaction&) = delete;
  SqliteWriteTransaction& operator=(const SqliteWriteTransaction&) = delete;

  // ObservationWriter
  StatusOr<InsertResult> InsertObservation(const NewObservation& obs) override;
  Status TieSession(int64_t session_id, const geometry::Rigid3& T_map_frame) override;
  void set_tie_point(int64_t newest_observation_id) override { tie_point_ = newest_observation_id; }
  bool ties_sessions() const override { return !new_ties_.empty(); }
  int64_t tie_seq() const override { return tie_seq_; }
  std::vector<int64_t> tied_session_ids() const override;
  // FusedMapWriter
  Status UpsertFused(const FusedRow& row) override;
  Status DeleteFused(uint64_t id) override;
  Status UpsertFusedPlane(const FusedPlaneRow& row) override;
  Status DeleteFusedPlane(uint64_t id) override;
  // SubmapWriter
  StatusOr<int64_t> InsertSubmap(const NewSubmap& submap) override;
  Status DeleteSubmap(int64_t id) override;
  StatusOr<MergeIds> RecordMerge(const NewMerge& merge) override;
  Status DecideMerge(int64_t id, MergeState state, const std::string& who, int64_t now_ns,
                     const std::string& reason) override;
  Status PlaceSubmap(int64_t submap_id, int64_t merge_id,
                     const geometry::Rigid3& T_map_submap) override;
  Status PutGlobalMap(const GlobalMapRecord& map) override;
  Status DeleteGlobalMap() override;
  // AuthWriter
  StatusOr<int64_t> InsertToken(const TokenRecord& token) override;
  Status RevokeToken(int64_t id, int64_t now_ns) override;
  Status AppendAudit(const AuditEntry& entry) override;
  StatusOr<int64_t> TrimDeniedAudit(int64_t keep) override;
  // SnapshotWriter
  Status InsertSnapshot(const FusionSnapshot& snapshot, int keep,
                        SnapshotParts parts = {}) override;
  Status InsertSnapshotPart(int64_t key, int index, std::string_view bytes) override;
  StatusOr<int> DeleteUnusedSnapshotParts(int limit) override;
  // Also returns the freed pages to the file system (databases made with
  // auto_vacuum=INCREMENTAL; see ClaimDatabase).
  StatusOr<uint64_t> DropRawObservations(int64_t received_before_ns, int limit) override;

  Status Commit() override;

 private:
  friend class SqliteStore;
  explicit SqliteWriteTransaction(SqliteStore* store) : store_(store) {}
  struct RobotDelta {
    uint64_t batches = 0, features = 0;
    int64_t last_seen_ns = 0;
  };
  StatusOr<int64_t> RobotId(const std::string& name, int64_t now_ns);
  StatusOr<SessionFrame> Session(int64_t robot_id, const std::string& name, FrameKind kind,
                                 int64_t now_ns);

  SqliteStore* store_;
  bool open_ = true;
  std::unordered_map<std::string, int64_t> new_robots_;
  std::unordered_map<std::string, SessionFrame> new_sessions_;  // key: robot_id/name
  std::unordered_map<int64_t, RobotDelta> robot_deltas_;
  std::unordered_map<int64_t, geometry::Rigid3> new_ties_;  // session id -> T_map_frame
  int64_t tie_point_ = 0;
  int64_t tie_seq_ = 0;  // of this transaction's ties, once one is made
  std::string payload_;  // scratch
};

class SqliteStore final : public Store {
 public:
  // Opens the database at `path`, creating it owner-only (mode 0600) when it
  // does not exist, and migrates its schema (sqlite/schema.h).
  static StatusOr<std::unique_ptr<SqliteStore>> Open(const std::string& path,
                                                     const StoreOptions& options);
  ~SqliteStore() override;

  StatusOr<std::unique_ptr<WriteTransaction>> BeginWrite() override;
  // Copies the WAL into the database file and truncates it.
  Status Checkpoint() override;
  // Needs kProbeFreeBytes free on the database's file system.
  Status ProbeWrite() override;
  static constexpr uint64_t kProbeFreeBytes = uint64_t{8} << 20;

  // ObservationReader
  Status ForEachObservation(const ObservationFn& fn) override;
  Status ForEachObservationBetween(int64_t after_id, int64_t through_id,
                                   const ObservationFn& fn) override;
  Status ForEachObservationOfSessions(const std::vector<int64_t>& session_ids, int64_t max_id,
                                      const ObservationFn& fn) override;
  StatusOr<int64_t> NewestObservationId() override;
  StatusOr<std::vector<SessionFrame>> ListSessions() override;
  StatusOr<SessionFrame> GetSession(int64_t session_id) const override;
  StatusOr<SessionFrame> FindSession(const std::string& robot,
                                     const std::string& session) const override;
  StatusOr<std::vector<RobotSummary>> ListRobots() override;
  std::string RobotName(int64_t robot_id) const override;
  StatusOr<std::vector<StampedPose>> RecentPoses(int64_t session_id, int limit) override;
  StatusOr<std::vector<SessionTrailRows>> ListTrails(const std::string& robot,
                                                     uint32_t max_points) override;
  // FusedMapReader
  StatusOr<std::vector<FusedRow>> LoadFused() override;
  StatusOr<std::vector<FusedPlaneRow>> LoadFusedPlanes() override;
  // SubmapReader
  StatusOr<std::vector<SubmapMeta>> ListSubmaps(const std::string& robot) override;
  StatusOr<SubmapMeta> GetSubmap(int64_t id) override;
  StatusOr<std::string> GetSubmapData(int64_t id) override;
  StatusOr<MergeRecord> GetMerge(int64_t id) override;
  StatusOr<std::vector<MergeRecord>> ListMerges() override;
  StatusOr<std::vector<SubmapPlacement>> ListPlacements() override;
  StatusOr<GlobalMapRecord> GetGlobalMap(bool with_data) override;
  // AuthReader
  StatusOr<TokenRecord> GetToken(int64_t id) override;
  StatusOr<std::vector<TokenRecord>> ListTokens() override;
  StatusOr<bool> AnyTokenEver() override;
  StatusOr<std::vector<AuditEntry>> ListAudit(int limit) override;
  // SnapshotReader
  StatusOr<FusionSnapshot> LatestSnapshot(int skip = 0) override;

  StatusOr<StoreCounts> Counts() override;
  uint64_t SizeBytes() const override;
  const std::string& path() const override { return path_; }

 private:
  friend class SqliteWriteTransaction;
  SqliteStore() = default;
  Status Prepare();
  // The observations with after_id < id <= through_id meeting the SQL
  // `condition` on o (observations) and s (sessions), in id order, read in
  // pages (see store.cc).
  Status ForEachObservationWhere(const std::string& condition, int64_t after_id, int64_t through_id,
                                 const ObservationFn& fn);
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

#endif  // MAPD_STORAGE_SQLITE_STORE_H_
