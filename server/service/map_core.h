// MapCore: the map server's state behind the RPC handlers.
//
// It owns the database (storage::Store), the fusion engine and two threads:
// - the writer: takes every queued batch, writes them in ONE transaction
//   (group commit) together with the fused-map rows that changed since the
//   last commit, commits, and only then calls each batch's callback. So an Ack
//   means "durable", and many robots share the cost of a commit.
// - the fuser: fuses committed observations in commit order and hands the
//   changed fused features back to the writer (one connection writes).
// Acks therefore never wait for fusion; the raw observations are the truth and
// the fused map follows them (a restart recomputes it from them). Queries see
// every batch acknowledged before they arrived (they wait for the fuser to
// catch up, up to a bound), and the writer stops taking batches while the
// fuser is more than max_fusion_backlog observations behind (backpressure).
//
// Other writes (submaps, merges, session ties) run on the writer thread too,
// each in a transaction of its own (ExecuteWrite). When a write ties session
// frames to the map frame, the fuser adds the newly tied sessions' stored
// observations to the engine, in id order, at that point of the commit order
// (a tie never moves, and sessions tied before are in the engine already, so
// nothing has to be removed or refused).
//
// Thread safety: every public method may be called from any thread.
#ifndef MAPD_SERVICE_MAP_CORE_H_
#define MAPD_SERVICE_MAP_CORE_H_

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <functional>
#include <future>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <random>
#include <shared_mutex>
#include <string>
#include <thread>
#include <unordered_map>
#include <unordered_set>
#include <vector>

#include "common/clock.h"
#include "common/status.h"
#include "fusion/engine.h"
#include "fusion/params.h"
#include "fusion/plane_engine.h"
#include "geometry/box2.h"
#include "service/core.h"
#include "service/delayed_calls.h"
#include "service/fusion_share.h"
#include "service/ingest_batch.h"
#include "service/latency_histogram.h"
#include "service/watch_hub.h"
#include "service/write_health.h"
#include "storage/postgres/observation_log.h"
#include "storage/store.h"

namespace mapd::service {

struct MapCoreOptions {
  std::string db_path;  // the SQLite file, unless `postgres` is set
  // A PostgreSQL connection string: the map `map_id` of that database
  // (storage/postgres/store.h) instead of a file.
  std::string postgres;
  std::string map_id;
  storage::PgOwnership ownership;  // who takes the map's lease (map_ownership.h)
  storage::StoreOptions store;
  fusion::FusionParams fusion;
  fusion::PlaneFusionParams planes;   // non-vertical planes (fusion/plane_engine.h)
  size_t max_group_batches = 4096;    // batches in one commit at most
  size_t max_fusion_backlog = 50000;  // committed, not yet fused observations at most
  // Before that: a robot keeping the fuser far busier than the others has its
  // batches refused (fusion_share.h), so that the others keep being acknowledged.
  FusionShareOptions fusion_share;
  double max_query_wait_s = 5.0;  // a query waits this long for the fuser at most
  // Snapshots of the fusion state (bounded mode): after this many fused
  // observations, or once the newest is this old and anything changed. A
  // restart loads the newest and replays only what came after it. 0 = never.
  uint64_t snapshot_every_observations = 20000;
  double snapshot_max_age_s = 60.0;
  // A snapshot's bytes are written in parts of this size, each in a commit of
  // its own between the batches' commits (one 35 MB commit held every robot's
  // acknowledgement for 350 ms); bytes, > 0.
  size_t snapshot_part_bytes = size_t{1} << 20;
  // Raw retention: observations received longer ago than this are deleted
  // once every kept snapshot reflects them (never those of a session not yet
  // tied to the map frame). 0 = keep them forever. Days.
  double raw_retention_days = 0.0;
  // Stop(): while the database refuses writes, how long the writer keeps
  // retrying what is queued before it gives up (those batches were never
  // acknowledged; the fused rows are recomputed at the next start), seconds.
  double stop_flush_s = 5.0;
  WatchOptions watch;  // the change feed (watch_hub.h)
  // Tests only; empty (the default) in mapd. While it returns true the fuser
  // thread neither starts recovering nor takes committed observations; Stop()
  // ends the hold (the held work is then left, as any backlog at a stop).
  // It lets a test look at a recovering core, or build a fusion backlog, on
  // a machine of any speed. Polled every few milliseconds, with a lock of the
  // core held: it must not call the core.
  std::function<bool()> hold_fuser_for_test;
  // Test hook: a recovery replay that serves (after a snapshot) waits before
  // each observation while this returns true, until Stop().
  std::function<bool()> hold_replay_for_test;
};

class MapCore final : public Core {
 public:
  // Opens (or creates) the database and returns at once; the fuser thread
  // then recovers the fused map: the newest usable snapshot, then the stored
  // observations after it, in the order the live server fused them (so the
  // map equals the one served before, bit for bit in bounded mode). Until
  // the snapshot is loaded (without one: until the whole replay is done),
  // ready() is false: batches and writes are refused with Unavailable
  // (retryable; nothing is stored) and queries should not be made. After a
  // snapshot the replay runs as a fusion backlog of a ready core
  // (CoreStats::replaying).
  static StatusOr<std::unique_ptr<MapCore>> Open(const MapCoreOptions& options);

  bool ready() const { return ready_.load(); }
  // `failure` of a write, or UNAVAILABLE saying the map was taken over when
  // the store no longer owns it (storage::Store::owns_map).
  Status UnlessTakenOver(const Status& failure) const;
  // How long the writer has been on its current round of work, seconds; 0
  // while it waits for work. A map's lease is renewed only while this stays
  // short (map_ownership.h): a writer stuck in the database gives its map up.
  double WriterBusyForS() const {
    const int64_t since = writer_busy_since_ns_.load();
    return since == 0 ? 0.0 : static_cast<double>(SteadyNowNs() - since) * 1e-9;
  }
  // Ok once recovered; else Unavailable saying how far recovery is.
  Status CheckReady() const override;
  // Runs `fn` once recovery succeeded (at once if it has), on any thread.
  void OnReady(std::function<void()> fn);
  // Waits until recovery ended (successfully or not); false on timeout.
  bool WaitUntilReady(std::chrono::duration<double> timeout) const;
  ~MapCore() override;  // Stop()

  // Queues a validated batch. `done` runs on the writer thread once the batch
  // is committed, found to be a duplicate, or refused; after Stop() it runs at
  // once with Unavailable.
  void Submit(IngestBatch batch, DoneCallback done) override;

  // Runs `write` on the writer thread in a transaction of its own and commits
  // it if `write` succeeds (else rolls back); returns once that is done, with
  // write's error or the commit's. When the transaction tied session frames
  // (WriteTransaction::TieSession), the fuser then fuses the stored
  // observations of those sessions; a query sent after this returns waits
  // for that (like for any committed batch). After Stop(): Unavailable,
  // nothing runs.
  Status ExecuteWrite(std::function<Status(storage::WriteTransaction*)> write) override;
  // An asynchronous write job: `done` runs on the writer thread with its
  // outcome (at once with Unavailable after Stop()). Nobody waits for it.
  void SubmitWrite(std::function<Status(storage::WriteTransaction*)> write,
                   std::function<void(const Status&)> done) override;

  // Stops taking batches, commits (and acknowledges) everything queued, stops
  // the fuser where it is (what it has not fused is committed and replayed at
  // the next start: a stop never waits for the fusion backlog), snapshots the
  // fusion state, checkpoints. Idempotent. `flush` false: while the database
  // refuses writes, refuse what is queued at once rather than retry for
  // stop_flush_s (a map taken over by another mapd: its writes never work).
  void Stop(bool flush = true);

  // The published lines and, if `planes` is not null, the published
  // non-vertical planes (same snapshot of the map; kind kLine leaves them
  // out; bbox: the boundary's ground projection meets the box).
  std::vector<FusedView> QueryFeatures(const FeatureQuery& query, uint64_t* map_version,
                                       std::vector<PlaneView>* planes = nullptr) const override;
  // Committed (acknowledged) observations the fuser has not reflected yet.
  uint64_t FusionBacklog() const override;
  CoreStats Stats() const override;
  // Whether the database takes writes (write_health.h); the server's health
  // listens to it.
  WriteHealth& write_health() { return write_health_; }
  storage::Store& store() override { return *store_; }
  WatchHub& watch_hub() override { return watch_hub_; }
  const MapCoreOptions& options() const { return options_; }

 private:
  struct Pending {
    IngestBatch batch;
    DoneCallback done;
    std::chrono::steady_clock::time_point queued;  // for ack_latency_
  };
  // Clusters whose published state changed (added, updated or removed); the
  // writer reads their current state from the engines when it writes them.
  struct FusedDelta {
    std::unordered_set<fusion::ClusterId> lines;   // engine_'s features
    std::unordered_set<fusion::ClusterId> planes;  // plane_engine_'s planes
    bool empty() const { return lines.empty() && planes.empty(); }
    size_t size() const { return lines.size() + planes.size(); }
    void clear() {
      lines.clear();
      planes.clear();
    }
    void Absorb(const FusedDelta& other) {
      lines.insert(other.lines.begin(), other.lines.end());
      planes.insert(other.planes.begin(), other.planes.end());
    }
  };

  explicit MapCore(const MapCoreOptions& options);
  struct WriteJob;
  struct ToFuse;
  // Fuser thread, at start (map_core_recovery.cc): engine_ from the newest
  // snapshot and the observations after it; then the fused table is synced.
  // After a snapshot the core is ready (serving) before the replay, which it
  // then treats as a fusion backlog. False if the engine is not in step with
  // the database (a failed or stopped recovery): nothing more may be fused.
  bool Recover();
  // Ready (or failed, `s`): the change feed starts at the current version,
  // OnReady callbacks run.
  void MarkReady(const Status& s);
  // What a replay will fuse: the sessions, the newest stored observation id,
  // the sessions fused as their observations come and the ties still to replay.
  struct ReplayPlan {
    std::vector<storage::SessionFrame> sessions;
    int64_t newest = 0;
    std::unordered_map<int64_t, geometry::Rigid3> streaming;
    std::map<std::pair<int64_t, int64_t>, std::vector<int64_t>> ties;  // (T, seq) -> sessions
  };
  StatusOr<ReplayPlan> PlanReplay();
  // Fuses, in the live order, every stored tied observation and tie after
  // (fused_through_id_, fused_tie_seq_), as planned. With `counted` (the
  // replay's part of committed_count_, at most), it also publishes rounds as
  // the fuser does and moves fused_count_ on, taking from *counted.
  Status Replay(ReplayPlan plan, uint64_t* counted);
  // Queues the fused-table rows that differ from engine_'s published map.
  Status QueueFusedTableSync();
  // Fuser thread: a snapshot when one is due (MapCoreOptions).
  void MaybeSnapshot(bool force);
  // Writer thread, after a snapshot is stored: raw retention, in rounds.
  void DropExpiredObservations();
  // Writer thread, after a snapshot is stored: the parts no snapshot names
  // any more, in rounds; then raw retention.
  void DropUnusedSnapshotParts();
  // A write nobody waits for and that may wait (snapshot parts, retention):
  // the writer runs at most one per round, after the batches, so that each
  // commits on its own between them. At Stop() the queued ones end with
  // Unavailable, not run.
  void SubmitBackgroundWrite(std::function<Status(storage::WriteTransaction*)> write,
                             std::function<void(const Status&)> done);
  // Fuser thread: the stored observations of newly tied sessions into engine_.
  // False if Stop() interrupted it (the engine then holds part of the tie).
  bool FuseTiedSessions(const ToFuse& tie, FusedDelta* delta);
  void RunWriteJobs(std::deque<std::shared_ptr<WriteJob>>& jobs);
  void WriterLoop();
  // Writer thread, at Stop() while the database refuses writes: refuses what
  // is queued (never acknowledged) and drops the fused rows (derived).
  void AbandonQueuedWrites(std::unique_lock<std::mutex>& lock);
  void CommitGroup(std::vector<Pending>& group, FusedDelta& fused);
  // Writer thread, queue_mu_ held: moves at most max_rows of fused_pending_
  // into `out` (empty).
  void TakeFusedRows(size_t max_rows, FusedDelta* out);
  void FuserLoop();
  // Fuser thread, after a failed recovery: waits for Stop() (see Recover).
  void ParkFuser();
  // Fuser thread: waits while options_.hold_fuser_for_test() says so, until
  // Stop() tells the fuser to stop.
  void HoldFuserForTest();
  // Fuser thread, after each round: what `delta` changed, read from the
  // engines, to the watchers (watch_hub.h); the version moves on even if
  // nothing published changed.
  void PublishChange(const FusedDelta& delta);
  // Writes the fused rows of `delta` (read from the engine) into `txn`.
  Status WriteFusedDelta(const FusedDelta& delta, storage::WriteTransaction* txn);
  // Waits until every observation committed so far is fused (or the timeout).
  void WaitForFuser(std::chrono::duration<double> timeout) const;
  // Projects one observation into the map frame and adds it to engine_;
  // `delta`, if not null, receives the clusters it changed.
  // REQUIRES: engine_mu_ held exclusively.
  void Fuse(const geometry::SensorObservation& features, int64_t observation_id, int64_t robot_id,
            const geometry::Rigid3& T_map_frame, FusedDelta* delta);
  storage::FusedRow ToRow(const fusion::FusedFeature& f) const;
  storage::FusedPlaneRow ToPlaneRow(const fusion::FusedPlane& f) const;
  std::vector<std::string> RobotNames(const std::vector<fusion::RobotId>& ids) const;
  // The same, comma-separated (the fused tables' robots column).
  std::string RobotList(const std::vector<fusion::RobotId>& ids) const;
  void RecordRate();

  const MapCoreOptions options_;
  const std::chrono::steady_clock::time_point started_ = std::chrono::steady_clock::now();
  std::unique_ptr<storage::Store> store_;

  mutable std::shared_mutex engine_mu_;  // writer: exclusive while fusing; queries: shared
  std::unique_ptr<fusion::FusionEngine> engine_;
  std::unique_ptr<fusion::PlaneFusionEngine> plane_engine_;  // same lock and thread as engine_
  std::atomic<uint64_t> map_version_{0};                     // observations reflected in the map
  std::atomic<uint64_t> published_version_{0};  // of the last change given to watch_hub_
  WatchHub watch_hub_{options_.watch};          // the change feed; the fuser publishes into it

  mutable std::mutex names_mu_;
  std::unordered_map<int64_t, std::string> robot_names_;

  std::mutex queue_mu_;
  std::condition_variable
      queue_cv_;               // the writer waits for work or for the fuser's backlog to drop
  std::deque<Pending> queue_;  // GUARDED_BY(queue_mu_)
  std::deque<std::shared_ptr<WriteJob>> write_jobs_;       // GUARDED_BY(queue_mu_)
  std::deque<std::shared_ptr<WriteJob>> background_jobs_;  // GUARDED_BY(queue_mu_)
  bool stopping_ = false;                                  // GUARDED_BY(queue_mu_)
  FusedDelta fused_pending_;  // GUARDED_BY(queue_mu_), fused by the fuser, not yet written
  std::chrono::steady_clock::time_point
      stop_flush_deadline_;  // GUARDED_BY(queue_mu_), set by Stop()
  WriteHealth write_health_;
  std::thread writer_;

  // Committed observations on their way to the fuser, in commit order.
  struct ToFuse {
    int64_t observation_id = 0;
    int64_t robot_id = 0;
    std::string robot;  // its name, for fusion_share_
    geometry::Rigid3 T_map_frame;
    geometry::SensorObservation features;
    // A tie, not an observation: these sessions were tied to the map frame
    // after observation tied_through_id was committed; fuse their stored
    // observations up to it (later ones are queued as observations).
    std::vector<int64_t> tied_sessions;
    int64_t tied_through_id = 0;
    int64_t tie_seq = 0;
  };
  mutable std::mutex fuse_mu_;
  mutable std::condition_variable fuse_cv_;  // the fuser waits for work; queries wait for the fuser
  std::deque<ToFuse> fuse_queue_;            // GUARDED_BY(fuse_mu_)
  uint64_t committed_count_ = 0;  // GUARDED_BY(fuse_mu_), observations handed to the fuser
  uint64_t fused_count_ = 0;      // GUARDED_BY(fuse_mu_), observations the fuser finished
  bool fuser_stopping_ = false;   // GUARDED_BY(fuse_mu_)
  bool stop_requested_ = false;   // GUARDED_BY(fuse_mu_): Stop() began; no more backpressure
  std::atomic<bool> fuser_abandon_{false};  // Stop(): the fuser leaves the rest of its work
  int64_t last_observation_id_ = 0;         // writer thread: the newest stored observation
  // Fuser thread: where the engine stands in the commit order (what a
  // snapshot of it reflects): every tied observation up to this id, every tie
  // up to this sequence number.
  int64_t fused_through_id_ = 0;
  int64_t fused_tie_seq_ = 0;
  // Fuser thread: which observations' cost is measured (seeded per process).
  std::minstd_rand cost_sampler_{std::random_device{}()};
  // Fuser thread (read by Stop() after joining it): Stop() interrupted a tie.
  bool partial_tie_ = false;
  std::chrono::steady_clock::time_point last_snapshot_ = std::chrono::steady_clock::now();
  std::atomic<uint64_t> fused_since_snapshot_{0};
  std::atomic<int64_t> snapshot_created_ns_{0};  // 0: none yet
  std::atomic<bool> snapshot_in_flight_{false};
  // The last snapshot's bytes, handed back by the writer once stored, so that
  // the next one is encoded into memory already mapped: a fresh 24 MB string
  // (the city at 1M) costs its growth copies and a page fault per 4 KiB: 144 ms
  // to encode against 52 ms reused (both with FNV-1a; tests/bench/snapshot_bench).
  std::mutex snapshot_spare_mu_;
  std::string snapshot_spare_;  // GUARDED_BY(snapshot_spare_mu_)

  // Recovery (Open, Recover).
  std::atomic<bool> ready_{false};
  std::atomic<int64_t> writer_busy_since_ns_{0};  // WriterBusyForS
  std::atomic<bool> replaying_{false};            // serving, with the recovery replay still going
  std::atomic<bool> cancel_recovery_{false};
  std::atomic<uint64_t> recovery_replayed_{0};
  std::atomic<int64_t> recovery_target_id_{0};
  mutable std::mutex ready_mu_;
  mutable std::condition_variable ready_cv_;
  std::vector<std::function<void()>> on_ready_;  // GUARDED_BY(ready_mu_)
  Status recovery_status_;                       // GUARDED_BY(ready_mu_)
  std::thread fuser_;

  std::atomic<uint64_t> batches_stored_{0};
  std::atomic<uint64_t> features_stored_{0};
  std::atomic<uint64_t> commits_{0};
  mutable std::mutex rate_mu_;
  struct RateSample {
    std::chrono::steady_clock::time_point t;
    uint64_t batches, features;
  };
  std::deque<RateSample> rate_samples_;  // GUARDED_BY(rate_mu_), one per 250 ms, 10 s deep
  LatencyHistogram ack_latency_;         // stored batches: queued to acknowledged
  FusionShare fusion_share_{options_.fusion_share};
  DelayedCalls delayed_refusals_;  // fusion share refusals, answered late (fusion_share.h)
};

}  // namespace mapd::service

#endif  // MAPD_SERVICE_MAP_CORE_H_
