// The observation intent (storage/observation_store.h) on PostgreSQL, for
// one map of a shared database.
//
// Opening a map takes its lease (map_lease.h), so that one mapd writes it at
// a time (a second gets FailedPrecondition while the lease runs), and every
// write transaction is fenced by the lease's epoch. Like the SQLite backend it has two connections:
// the writer's, used by one thread in group transactions, and a reader's, serialised on a mutex.
// Observation ids are given by the writer (the newest committed + 1): one
// mapd writes a map at a time (its owner), so ids follow the commit order,
// which snapshots and replay rely on, and no sequence gaps or cross-map
// contention come with them.
//
// A transaction is shared with the other intents: PgWriteScope runs BEGIN,
// COMMIT or ROLLBACK on the writer connection; PgObservationWriter writes in
// it and must be told BeforeCommit() (it flushes the robots' counters) and
// AfterCommit() (it publishes the new robots, sessions and ties to the caches).
#ifndef MAPD_STORAGE_POSTGRES_OBSERVATION_LOG_H_
#define MAPD_STORAGE_POSTGRES_OBSERVATION_LOG_H_

#include <atomic>
#include <cstdint>
#include <memory>
#include <mutex>
#include <string>
#include <unordered_map>
#include <vector>

#include "storage/observation_store.h"
#include "storage/postgres/map_lease.h"
#include "storage/postgres/pq.h"

namespace mapd::storage {

class PgObservationWriter;

// BEGIN on construction (check status()), ROLLBACK when destroyed unless committed.
class PgWriteScope {
 public:
  explicit PgWriteScope(PgConnection* conn);
  ~PgWriteScope();
  PgWriteScope(const PgWriteScope&) = delete;
  PgWriteScope& operator=(const PgWriteScope&) = delete;
  const Status& status() const { return begun_; }
  Status Commit();

 private:
  PgConnection* conn_;
  Status begun_;
  bool open_ = false;
};

// Who opens a map, and whether to own it.
struct PgOwnership {
  // false: without the map's lease, for tools that write tokens and audit
  // rows beside a running mapd (the writer then refuses map data).
  bool own = true;
  PgInstance instance = DefaultPgInstance();
  double lease_ttl_s = 10;  // the lease Open takes; the owner renews it
  // How long the writer's session may sit in an open transaction before
  // PostgreSQL ends it: bounds how long a paused owner holds a takeover back.
  double idle_in_transaction_s = 10;
};

class PgObservationLog final : public ObservationReader {
 public:
  // Connects twice to `conninfo`, migrates the schema, makes `map_id`'s
  // partition, takes its lease (`ownership`) and loads the map's robots and
  // sessions. FailedPrecondition naming the owner while another holds it.
  static StatusOr<std::unique_ptr<PgObservationLog>> Open(const std::string& conninfo,
                                                          const std::string& map_id,
                                                          const PgOwnership& ownership = {});
  // Lets the lease lapse (ReleaseMapLease), so that another takes the map at once.
  ~PgObservationLog() override;
  // Holds the map's lease; false once a fence found it taken over.
  bool owner() const { return owner_; }
  // The lease taken at Open (epoch 0 when not an owner).
  const MapLease& lease() const { return lease_; }
  // Lets the lease lapse now and stops owning the map (a handoff): another
  // instance takes it at once. Writer connection: the writer must be idle.
  Status Release();
  // Closes both connections for good, releasing the lease first if still
  // held: the map is served elsewhere now and its writer has stopped. Every
  // later read, write or reconnect answers `why`, and nothing connects again,
  // so a map handed off or dropped holds no connection while calls that
  // started before still hold it.
  void Close(const Status& why);
  // Ok until Close, then its `why`.
  Status CheckOpen();
  // Writer thread, first in each write transaction of the map's data:
  // FenceMapLease. Once it finds the lease taken over, this log stops
  // owning the map and every later write of its data is refused.
  Status Fence();

  // The writer connection (writer thread only), for PgWriteScope and the
  // other intents' writers.
  PgConnection& writer() { return writer_; }
  // Runs `sql` (SET ...) on the writer connection, now and after a reconnect.
  Status SetWriterSession(const std::string& sql);
  // Writer thread, after a write failed: when the writer's connection is
  // broken (PostgreSQL restarted, the network failed), connects again and
  // checks the lease is still this log's. FailedPrecondition if another
  // mapd took the map meanwhile (this one then refuses map data); the
  // connection's error while PostgreSQL is still away.
  Status Reconnect();
  // A writer for the transaction open on writer() (writer thread only).
  std::unique_ptr<PgObservationWriter> NewWriter();

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

  const std::string& map_id() const { return map_id_; }
  const std::string& partition() const { return partition_; }

 private:
  friend class PgObservationWriter;
  friend class PgStore;  // shares the connections with the other intents
  PgObservationLog() = default;
  // Stops owning the map for good: `why` answers every later write.
  void Disown(const Status& why);
  Status LoadCaches();
  // A query on reader_, connected again and retried once if the connection
  // broke. REQUIRES: reader_mu_ held.
  StatusOr<PgResult> ReadQuery(const std::string& sql, const PgParams& params = {});
  // Rows with after_id < id <= through_id and `condition` (SQL on o, with
  // parameters from $4 on), in id order, in pages; fn runs unlocked.
  Status ForEachWhere(const std::string& condition, const std::vector<int64_t>& session_ids,
                      int64_t after_id, int64_t through_id, const ObservationFn& fn);
  static std::string SessionKey(int64_t robot_id, const std::string& name) {
    return std::to_string(robot_id) + "/" + name;
  }

  std::string map_id_;
  std::string conninfo_;
  std::vector<std::string> writer_session_;  // SetWriterSession
  int64_t map_num_ = 0;                      // maps.num
  std::string partition_;                    // the map's observations' table
  std::atomic<bool> owner_{false};           // holds the map's lease
  MapLease lease_;                           // set at Open
  Status disowned_;                          // why owner_ went false (writer thread)
  PgConnection writer_;
  PgConnection reader_;
  std::mutex reader_mu_;  // guards reader_ and closed_
  Status closed_;         // set by Close: why nothing connects again

  // Committed robots and sessions, and the newest committed observation id.
  mutable std::mutex cache_mu_;
  std::unordered_map<std::string, int64_t> robot_ids_;
  std::unordered_map<int64_t, std::string> robot_names_;
  std::unordered_map<std::string, SessionFrame> sessions_;
  int64_t max_tie_seq_ = 0;         // GUARDED_BY(cache_mu_)
  int64_t newest_observation_ = 0;  // GUARDED_BY(cache_mu_)
};

class PgObservationWriter final : public ObservationWriter {
 public:
  StatusOr<InsertResult> InsertObservation(const NewObservation& obs) override;
  // One INSERT ... SELECT FROM unnest(...) for the whole group (plus one
  // SELECT when some were stored before): a round trip per group, not per batch.
  StatusOr<std::vector<StatusOr<InsertResult>>> InsertObservations(
      const std::vector<NewObservation>& batches) override;
  Status TieSession(int64_t session_id, const geometry::Rigid3& T_map_frame) override;
  void set_tie_point(int64_t newest_observation_id) override { tie_point_ = newest_observation_id; }
  bool ties_sessions() const override { return !new_ties_.empty(); }
  int64_t tie_seq() const override { return tie_seq_; }
  std::vector<int64_t> tied_session_ids() const override;

  // Before COMMIT, in the transaction: the robots' batch and feature counts.
  Status BeforeCommit();
  // After COMMIT succeeded: the caches learn what this transaction made.
  void AfterCommit();

  // For the other intents in the same transaction (submaps): the robot's
  // id, made on first sight, and a session's id (0 if it has none).
  StatusOr<int64_t> RobotId(const std::string& name, int64_t now_ns);
  int64_t SessionId(int64_t robot_id, const std::string& name) const;
  // FailedPrecondition unless the log holds the map's lease: robots,
  // sessions, observations and ties (and so submaps and merges, which make
  // robots) are written by the map's owner only.
  Status CheckOwner() const;

 private:
  friend class PgObservationLog;
  explicit PgObservationWriter(PgObservationLog* log);
  struct RobotDelta {
    uint64_t batches = 0, features = 0;
    int64_t last_seen_ns = 0;
  };
  StatusOr<SessionFrame> Session(int64_t robot_id, const std::string& name, FrameKind kind,
                                 int64_t now_ns);
  // The batch's session frame (robot and session made on first sight);
  // InvalidArgument when its frame kind disagrees with the session's.
  StatusOr<SessionFrame> FrameOf(const NewObservation& obs);
  void CountStored(const NewObservation& obs, int64_t robot_id);

  PgObservationLog* log_;
  int64_t next_id_;  // the id the next stored observation gets
  std::unordered_map<std::string, int64_t> new_robots_;
  std::unordered_map<std::string, SessionFrame> new_sessions_;
  std::unordered_map<int64_t, RobotDelta> robot_deltas_;
  std::unordered_map<int64_t, geometry::Rigid3> new_ties_;
  int64_t tie_point_ = 0;
  int64_t tie_seq_ = 0;
};

}  // namespace mapd::storage

#endif  // MAPD_STORAGE_POSTGRES_OBSERVATION_LOG_H_
