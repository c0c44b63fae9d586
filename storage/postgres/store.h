// storage::Store on PostgreSQL: one map of a database that holds many (every
// table keyed by map id; schema.h). The observation intent is
// PgObservationLog (observation_log.h), whose two connections the other
// intents share: the writer's for transactions, the reader's under its mutex.
// The methods are spread over files by intent: fused_map_store.cc,
// snapshot_store.cc, submap_store.cc, auth_store.cc; store.cc holds the rest.
//
// Durability (StoreOptions::synchronous_full): false = synchronous_commit
// local (a commit is on the primary's disk); true = on, and Open refuses a
// server without synchronous standbys, where "on" would silently mean local.
#ifndef MAPD_STORAGE_POSTGRES_STORE_H_
#define MAPD_STORAGE_POSTGRES_STORE_H_

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "storage/postgres/observation_log.h"
#include "storage/store.h"

namespace mapd::storage {

class PgStore;

class PgWriteTransaction final : public WriteTransaction {
 public:
  ~PgWriteTransaction() override = default;

  // ObservationWriter (PgObservationWriter)
  StatusOr<InsertResult> InsertObservation(const NewObservation& obs) override {
    return obs_->InsertObservation(obs);
  }
  StatusOr<std::vector<StatusOr<InsertResult>>> InsertObservations(
      const std::vector<NewObservation>& batches) override {
    return obs_->InsertObservations(batches);
  }
  Status TieSession(int64_t session_id, const geometry::Rigid3& T_map_frame) override {
    return obs_->TieSession(session_id, T_map_frame);
  }
  void set_tie_point(int64_t id) override { obs_->set_tie_point(id); }
  bool ties_sessions() const override { return obs_->ties_sessions(); }
  int64_t tie_seq() const override { return obs_->tie_seq(); }
  std::vector<int64_t> tied_session_ids() const override { return obs_->tied_session_ids(); }
  // FusedMapWriter
  Status UpsertFused(const FusedRow& row) override;
  Status DeleteFused(uint64_t id) override;
  Status UpsertFusedPlane(const FusedPlaneRow& row) override;
  Status DeleteFusedPlane(uint64_t id) override;
  // One INSERT ... ON CONFLICT per list and one DELETE: a round trip each.
  Status WriteFused(const std::vector<FusedRow>& upserts,
                    const std::vector<uint64_t>& deletes) override;
  Status WriteFusedPlanes(const std::vector<FusedPlaneRow>& upserts,
                          const std::vector<uint64_t>& deletes) override;
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
  StatusOr<uint64_t> DropRawObservations(int64_t received_before_ns, int limit) override;

  Status Commit() override;

 private:
  friend class PgStore;
  explicit PgWriteTransaction(PgStore* store);
  // A query on the writer connection, with the map id as $1.
  StatusOr<PgResult> Query(const std::string& sql, PgParams params);
  PgParams MapParams() const;
  // Stores `bytes` as `owner`'s parts in blob_parts (replacing any).
  Status PutBlob(const std::string& owner, std::string_view bytes);

  PgStore* store_;
  PgWriteScope scope_;
  std::unique_ptr<PgObservationWriter> obs_;
};

class PgStore final : public Store {
 public:
  // Connects to `conninfo` (libpq: "host=... dbname=..." or a
  // postgresql:// URI), migrates the schema and opens map `map_id`, taking
  // its lease as `ownership` says (PgObservationLog::Open). Not owning is
  // for `mapd token` beside a running mapd; map data is then refused.
  static StatusOr<std::unique_ptr<PgStore>> Open(const std::string& conninfo,
                                                 const std::string& map_id,
                                                 const StoreOptions& options,
                                                 const PgOwnership& ownership = {});
  ~PgStore() override = default;

  // Fenced (PgObservationLog::Fence): FailedPrecondition naming the new
  // owner once the map was taken over.
  StatusOr<std::unique_ptr<WriteTransaction>> BeginWrite() override;
  // The lease taken at Open, and whether it is still held as far as the
  // fence knows (the lease's renewal is the owner's, on a connection of its own).
  const MapLease& lease() const { return log_->lease(); }
  bool owner() const { return log_->owner(); }
  bool owns_map() const override { return log_->owner(); }
  // Hands the map off (PgObservationLog::Release), once its writer stopped.
  Status ReleaseLease() { return log_->Release(); }
  // Closes the map's connections for good (PgObservationLog::Close), once it
  // is served elsewhere and its writer stopped.
  void Close(const Status& why) { log_->Close(why); }
  // Nothing to do: PostgreSQL checkpoints and vacuums by itself.
  Status Checkpoint() override { return Status::Ok(); }
  // Connects again if the writer's connection broke (PgObservationLog::
  // Reconnect), then a fenced 1 MiB write commits (and is deleted): the
  // server takes writes again.
  Status ProbeWrite() override;

  // ObservationReader (PgObservationLog)
  Status ForEachObservation(const ObservationFn& fn) override {
    return log_->ForEachObservation(fn);
  }
  Status ForEachObservationBetween(int64_t after_id, int64_t through_id,
                                   const ObservationFn& fn) override {
    return log_->ForEachObservationBetween(after_id, through_id, fn);
  }
  Status ForEachObservationOfSessions(const std::vector<int64_t>& session_ids, int64_t max_id,
                                      const ObservationFn& fn) override {
    return log_->ForEachObservationOfSessions(session_ids, max_id, fn);
  }
  StatusOr<int64_t> NewestObservationId() override { return log_->NewestObservationId(); }
  StatusOr<std::vector<SessionFrame>> ListSessions() override { return log_->ListSessions(); }
  StatusOr<SessionFrame> GetSession(int64_t session_id) const override {
    return log_->GetSession(session_id);
  }
  StatusOr<SessionFrame> FindSession(const std::string& robot,
                                     const std::string& session) const override {
    return log_->FindSession(robot, session);
  }
  StatusOr<std::vector<RobotSummary>> ListRobots() override { return log_->ListRobots(); }
  std::string RobotName(int64_t robot_id) const override { return log_->RobotName(robot_id); }
  StatusOr<std::vector<StampedPose>> RecentPoses(int64_t session_id, int limit) override {
    return log_->RecentPoses(session_id, limit);
  }
  StatusOr<std::vector<SessionTrailRows>> ListTrails(const std::string& robot,
                                                     uint32_t max_points) override {
    return log_->ListTrails(robot, max_points);
  }
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
  // The map's observation partition with its indexes, bytes (blobs live in
  // shared tables and are not counted).
  uint64_t SizeBytes() const override;
  // "postgresql map <id>", for operators (never the connection string,
  // which may hold a password).
  const std::string& path() const override { return path_; }

 private:
  friend class PgWriteTransaction;
  PgStore() = default;
  // A query on the reader connection (under its mutex), with the map id as $1.
  StatusOr<PgResult> Read(const std::string& sql, PgParams params) const;
  PgParams MapParams() const;
  // `owner`'s parts from blob_parts, concatenated; NotFound naming `what`.
  StatusOr<std::string> GetBlob(const std::string& owner, const std::string& what) const;

  std::unique_ptr<PgObservationLog> log_;
  std::string path_;
};

}  // namespace mapd::storage

#endif  // MAPD_STORAGE_POSTGRES_STORE_H_
