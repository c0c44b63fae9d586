#include "service/map_core.h"

#include <pthread.h>
#include <sys/resource.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <algorithm>
#include <iterator>

#include "common/clock.h"
#include "fusion/projection.h"
#include "service/feature_filter.h"
#include "service/log.h"
#include "storage/postgres/store.h"
#include "storage/sqlite/store.h"

namespace mapd::service {
namespace {

using Clock = std::chrono::steady_clock;

// The fuser's nice value (see where it is set).
constexpr int kFuserNice = 5;
// Fused rows written with one group commit at most (WriterLoop).
constexpr size_t kMaxFusedRowsPerCommit = 512;
// Observations the fuser takes per round at most (FuserLoop). Its progress
// (fused_count_, which the writer's backpressure and read-your-writes waits
// watch) moves once per round, and snapshots are taken between rounds. A
// round of the whole queue, up to limits.max_fusion_backlog (50,000)
// observations, is ~3 s of fusion during which the writer sees the backlog
// full and holds every commit: the soak's p99 acknowledgement was 1-3 s
// (docs/long-running.md). 512 are 30-60 ms of fusion at the soak's rates.
constexpr size_t kMaxObservationsPerFuseRound = 512;

// Records one change feed into a set of clusters to rewrite.
void Accumulate(const fusion::ChangeFeed& feed, std::unordered_set<fusion::ClusterId>* delta) {
  for (const auto* ids : {&feed.added, &feed.updated, &feed.removed}) {
    delta->insert(ids->begin(), ids->end());
  }
}

}  // namespace

struct MapCore::WriteJob {
  std::function<Status(storage::WriteTransaction*)> write;
  std::function<void(const Status&)> done;
};

MapCore::MapCore(const MapCoreOptions& options) : options_(options) {}

StatusOr<std::unique_ptr<MapCore>> MapCore::Open(const MapCoreOptions& options) {
  Status params = options.fusion.Validate();
  if (!params.ok()) return Status::InvalidArgument("fusion parameters: " + params.message());
  params = options.planes.Validate();
  if (!params.ok()) return Status::InvalidArgument("plane fusion parameters: " + params.message());
  if (options.snapshot_part_bytes == 0)
    return Status::InvalidArgument("snapshot_part_bytes must be > 0");
  std::unique_ptr<MapCore> core(new MapCore(options));
  if (!options.postgres.empty()) {
    StatusOr<std::unique_ptr<storage::PgStore>> store =
        storage::PgStore::Open(options.postgres, options.map_id, options.store, options.ownership);
    if (!store.ok()) {
      return Status(store.status().code(), "cannot open map '" + options.map_id +
                                               "' on PostgreSQL: " + store.status().message());
    }
    core->store_ = std::move(store).value();
  } else {
    StatusOr<std::unique_ptr<storage::SqliteStore>> store =
        storage::SqliteStore::Open(options.db_path, options.store);
    if (!store.ok()) {
      return Status(store.status().code(), "cannot open the database '" + options.db_path +
                                               "': " + store.status().message());
    }
    core->store_ = std::move(store).value();
  }
  StatusOr<std::vector<storage::RobotSummary>> robots = core->store_->ListRobots();
  if (!robots.ok()) return robots.status();
  for (const auto& r : *robots) core->robot_names_[r.id] = r.name;
  StatusOr<int64_t> newest = core->store_->NewestObservationId();
  if (!newest.ok()) return newest.status();
  core->last_observation_id_ = *newest;
  core->engine_ = std::make_unique<fusion::FusionEngine>(options.fusion);
  core->plane_engine_ = std::make_unique<fusion::PlaneFusionEngine>(options.planes);
  core->writer_ = std::thread([c = core.get()] {
    pthread_setname_np(pthread_self(), "mapd-writer");  // for top -H and benchmarks
    c->WriterLoop();
  });
  core->fuser_ = std::thread([c = core.get()] {
    pthread_setname_np(pthread_self(), "mapd-fuser");
    c->HoldFuserForTest();
    // Recovery runs at the process's priority: until it ends the map is not
    // served (a replay from scratch) or its reads wait for it (from a
    // snapshot), and a busy instance taking over a dead one's maps must not
    // starve it.
    const bool recovered = c->Recover();
    // Then fusion is throughput work and acks wait only for the writer: on a
    // busy machine the threads that answer robots get the CPU first (issue
    // 46: one robot's junk kept the fuser at 100 % and the others' acks
    // waited for a core). Linux: a thread's nice value is its own.
    setpriority(PRIO_PROCESS, static_cast<id_t>(syscall(SYS_gettid)), kFuserNice);
    if (recovered) {
      c->FuserLoop();
    } else {
      c->ParkFuser();
    }
  });
  return core;
}

MapCore::~MapCore() { Stop(); }

Status MapCore::CheckReady() const {
  if (ready_.load()) {
    std::lock_guard<std::mutex> lock(ready_mu_);
    return recovery_status_;
  }
  return Status::Unavailable("mapd is recovering its fused map (" +
                             std::to_string(recovery_replayed_.load()) +
                             " observations replayed, up to id " +
                             std::to_string(recovery_target_id_.load()) + "); retry in a moment");
}

bool MapCore::WaitUntilReady(std::chrono::duration<double> timeout) const {
  std::unique_lock<std::mutex> lock(ready_mu_);
  return ready_cv_.wait_for(lock, timeout, [this] { return ready_.load(); });
}

void MapCore::OnReady(std::function<void()> fn) {
  {
    std::lock_guard<std::mutex> lock(ready_mu_);
    if (!ready_.load()) {
      on_ready_.push_back(std::move(fn));
      return;
    }
  }
  fn();
}

Status MapCore::ExecuteWrite(std::function<Status(storage::WriteTransaction*)> write) {
  MAPD_RETURN_IF_ERROR(CheckReady());
  MAPD_RETURN_IF_ERROR(write_health_.status());  // refused now, not queued behind a failing disk
  auto done = std::make_shared<std::promise<Status>>();
  std::future<Status> result = done->get_future();
  {
    std::lock_guard<std::mutex> lock(queue_mu_);
    if (stopping_) return Status::Unavailable("mapd is shutting down; nothing was written");
    write_jobs_.push_back(std::make_shared<WriteJob>(
        WriteJob{std::move(write), [done](const Status& s) { done->set_value(s); }}));
    queue_cv_.notify_one();
  }
  return result.get();
}

void MapCore::SubmitWrite(std::function<Status(storage::WriteTransaction*)> write,
                          std::function<void(const Status&)> done) {
  std::lock_guard<std::mutex> lock(queue_mu_);
  if (stopping_) {
    done(Status::Unavailable("mapd is shutting down"));
    return;
  }
  write_jobs_.push_back(std::make_shared<WriteJob>(WriteJob{std::move(write), std::move(done)}));
  queue_cv_.notify_one();
}

void MapCore::SubmitBackgroundWrite(std::function<Status(storage::WriteTransaction*)> write,
                                    std::function<void(const Status&)> done) {
  {
    std::lock_guard<std::mutex> lock(queue_mu_);
    if (!stopping_) {
      background_jobs_.push_back(
          std::make_shared<WriteJob>(WriteJob{std::move(write), std::move(done)}));
      queue_cv_.notify_one();
      return;
    }
  }
  done(Status::Unavailable("mapd is shutting down"));
}

void MapCore::RunWriteJobs(std::deque<std::shared_ptr<WriteJob>>& jobs) {
  for (const std::shared_ptr<WriteJob>& job : jobs) {
    StatusOr<std::unique_ptr<storage::WriteTransaction>> txn = store_->BeginWrite();
    Status s = txn.status();
    std::vector<int64_t> tied;
    int64_t tie_seq = 0;
    if (s.ok()) {
      (*txn)->set_tie_point(last_observation_id_);
      s = job->write(txn->get());
    }
    if (s.ok()) {
      tied = (*txn)->tied_session_ids();
      tie_seq = (*txn)->tie_seq();
      s = (*txn)->Commit();
    }
    txn = Status::Ok();  // ends the transaction (rolls back unless committed)
    s = UnlessTakenOver(s);
    write_health_.Record(s);
    if (s.ok() && !tied.empty()) {
      // In commit order with the observations: the tied sessions' stored
      // observations are all <= last_observation_id_ (later ones are queued
      // as tied observations behind this marker).
      std::lock_guard<std::mutex> lock(fuse_mu_);
      ToFuse marker;
      marker.tied_sessions = std::move(tied);
      marker.tied_through_id = last_observation_id_;
      marker.tie_seq = tie_seq;
      fuse_queue_.push_back(std::move(marker));
      committed_count_ += 1;
      fuse_cv_.notify_all();
    }
    job->done(s);
  }
  jobs.clear();
}

void MapCore::Submit(IngestBatch batch, DoneCallback done) {
  if (Status ready = CheckReady(); !ready.ok()) {
    done({BatchOutcome::Kind::kRejected, ready});
    return;
  }
  // While the database refuses writes, batches are refused at once (robots
  // resend them) rather than piling up in memory; the writer probes.
  if (Status writable = write_health_.status(); !writable.ok()) {
    done({BatchOutcome::Kind::kRejected, writable});
    return;
  }
  // A robot keeping the fuser far busier than the others waits, not them.
  if (Status fair = fusion_share_.Admit(batch.robot); !fair.ok()) {
    delayed_refusals_.Post(
        std::chrono::duration_cast<Clock::duration>(
            std::chrono::duration<double>(options_.fusion_share.refusal_delay_s)),
        [done = std::move(done), fair] {
          done({BatchOutcome::Kind::kRejected, fair});
        });
    return;
  }
  {
    std::lock_guard<std::mutex> lock(queue_mu_);
    if (!stopping_) {
      queue_.push_back({std::move(batch), std::move(done), Clock::now()});
      queue_cv_.notify_one();
      return;
    }
  }
  done({BatchOutcome::Kind::kRejected,
        Status::Unavailable("mapd is shutting down; resend this batch after reconnecting")});
}

Status MapCore::UnlessTakenOver(const Status& failure) const {
  if (failure.ok() || store_->owns_map()) return failure;
  // For good, and not the batch's fault: UNAVAILABLE, so the robot resends it
  // (to the map's new owner), and the writer pauses between tries instead of
  // retrying at once (write_health.h) until the map is dropped here.
  return Status::Unavailable("map '" + options_.map_id +
                             "' was taken over by another mapd; resend there (" +
                             failure.message() + ")");
}

void MapCore::Stop(bool flush) {
  cancel_recovery_ = true;
  delayed_refusals_.Stop();  // the refusals still waiting are answered now
  watch_hub_.Close();        // watches end at once (MapServer closes them earlier)
  {
    // Lifts the writer's backpressure: what is queued gets committed now.
    std::lock_guard<std::mutex> lock(fuse_mu_);
    stop_requested_ = true;
    fuse_cv_.notify_all();
  }
  std::deque<std::shared_ptr<WriteJob>> background;
  {
    std::lock_guard<std::mutex> lock(queue_mu_);
    stopping_ = true;
    stop_flush_deadline_ =
        std::chrono::steady_clock::now() +
        std::chrono::milliseconds(static_cast<int64_t>(flush ? options_.stop_flush_s * 1000 : 0));
    background.swap(background_jobs_);
    queue_cv_.notify_all();
  }
  // Every queued batch is committed and acknowledged, or, if the database
  // still refuses writes after stop_flush_s, refused (never acknowledged).
  if (writer_.joinable()) writer_.join();
  // Background writes are not waited for: a stop writes its own snapshot, and
  // retention goes on after the next one. Told only now: their callbacks share
  // state with the job the writer may have been running (a snapshot's parts).
  for (const std::shared_ptr<WriteJob>& job : background)
    job->done(Status::Unavailable("mapd is shutting down"));
  {
    std::lock_guard<std::mutex> lock(fuse_mu_);
    fuser_stopping_ = true;
    fuser_abandon_ = true;
    fuse_cv_.notify_all();
  }
  // The fuser stops at its next observation: what it has not fused is
  // committed, and the next start replays it after the snapshot taken below.
  // So a stop does not wait for the fusion backlog.
  const bool first_stop = fuser_.joinable();
  if (first_stop) fuser_.join();
  if (first_stop) {
    std::lock_guard<std::mutex> lock(fuse_mu_);
    if (committed_count_ > fused_count_) {
      Log(LogLevel::kInfo, "fusion_backlog_left",
          {{"observations", std::to_string(committed_count_ - fused_count_)},
           {"action", "replayed at the next start"}});
    }
  }
  // The writer is gone, so this thread is now the one writer: persist the last
  // fused changes and checkpoint.
  FusedDelta last;
  {
    std::lock_guard<std::mutex> lock(queue_mu_);
    std::swap(last, fused_pending_);
  }
  if (!last.empty() && store_ && write_health_.ok()) {
    StatusOr<std::unique_ptr<storage::WriteTransaction>> txn = store_->BeginWrite();
    Status s = txn.ok() ? WriteFusedDelta(last, txn->get()) : txn.status();
    if (s.ok()) s = (*txn)->Commit();
    if (!s.ok()) Log(LogLevel::kWarn, "fused_table_write_failed", {{"error", s.ToString()}});
  }
  // A snapshot of the final state makes the next start replay nothing.
  if (partial_tie_) {
    if (first_stop) {
      Log(LogLevel::kInfo, "stop_during_tie",
          {{"action", "no snapshot of a half-fused tie; the next start replays it"}});
    }
  } else if (store_ && ready_.load() && CheckReady().ok() && write_health_.ok()) {
    MaybeSnapshot(/*force=*/true);
  }
  if (store_) {
    Status s = store_->Checkpoint();
    if (!s.ok()) Log(LogLevel::kWarn, "checkpoint_failed", {{"error", s.ToString()}});
  }
}

void MapCore::WriterLoop() {
  std::vector<Pending> group;
  FusedDelta fused;
  std::deque<std::shared_ptr<WriteJob>> jobs;
  for (;;) {
    writer_busy_since_ns_ = 0;  // waiting for work (or for the database to come back)
    // Backpressure: while the fuser is far behind, commit no new batches, so
    // robots see slower acks instead of the server growing without bound.
    // Other writes (submaps, merges, deletes, fused features) go on: an
    // upload must not wait behind the fusion backlog.
    bool backlogged = false;
    {
      std::lock_guard<std::mutex> lock(fuse_mu_);
      backlogged =
          committed_count_ - fused_count_ > options_.max_fusion_backlog && !stop_requested_;
    }
    bool probe = false, retry = true;  // retry: take the queued work this round
    {
      std::unique_lock<std::mutex> lock(queue_mu_);
      // While backlogged, queued batches are not work (see above).
      const auto has_work = [&] {
        return (!backlogged && !queue_.empty()) || !fused_pending_.empty() ||
               !write_jobs_.empty() || !background_jobs_.empty();
      };
      if (!write_health_.ok()) {
        // A failing database is retried after a pause, not in a tight loop;
        // Stop() cuts a long pause short.
        const bool was_stopping = stopping_;
        const auto pause = was_stopping ? std::chrono::milliseconds(100) : write_health_.Backoff();
        queue_cv_.wait_for(lock, pause, [&] { return stopping_ != was_stopping; });
        if (stopping_ && !write_health_.ok() &&
            std::chrono::steady_clock::now() >= stop_flush_deadline_) {
          AbandonQueuedWrites(lock);
          break;
        }
        // Probe whether writes work again, then retry the work (refused
        // again while the database still fails): the probe is what connects
        // to PostgreSQL again after it restarted (a commit on the broken
        // connection fails at BEGIN for ever), and fused rows that failed to
        // commit stay pending, so there may always be work to retry.
        probe = true;
        if (queue_.empty() && fused_pending_.empty() && write_jobs_.empty() &&
            background_jobs_.empty()) {
          if (stopping_) break;  // nothing left to retry
          retry = false;
        }
      } else {
        if (backlogged) {
          // The fuser's progress is signalled on fuse_cv_, not here: look again soon.
          queue_cv_.wait_for(lock, std::chrono::milliseconds(20),
                             [&] { return has_work() || stopping_; });
        } else {
          queue_cv_.wait(lock, [&] { return has_work() || stopping_; });
        }
        if (queue_.empty() && fused_pending_.empty() && write_jobs_.empty() && stopping_)
          break;  // nothing left
        if (!has_work()) continue;
      }
      if (retry) {
        jobs.swap(write_jobs_);
        // One background write per round, after this round's batches.
        if (!background_jobs_.empty()) {
          jobs.push_back(std::move(background_jobs_.front()));
          background_jobs_.pop_front();
        }
        const size_t n = backlogged ? 0 : std::min(queue_.size(), options_.max_group_batches);
        group.reserve(n);
        for (size_t i = 0; i < n; ++i) {
          group.push_back(std::move(queue_.front()));
          queue_.pop_front();
        }
        // At most kMaxFusedRowsPerCommit fused rows per commit: writing
        // 5,000 took 110-180 ms, and the batches queued meanwhile waited
        // (issue 46). The rest stay pending: the next commits take them.
        TakeFusedRows(kMaxFusedRowsPerCommit, &fused);
      }
    }
    writer_busy_since_ns_ = SteadyNowNs();
    if (probe) write_health_.Record(store_->ProbeWrite(), WriteHealth::Attempt::kProbe);
    if (!retry) continue;
    if (!group.empty() || !fused.empty()) CommitGroup(group, fused);
    group.clear();
    fused.clear();
    RunWriteJobs(jobs);
  }
}

void MapCore::TakeFusedRows(size_t max_rows, FusedDelta* out) {
  if (fused_pending_.size() <= max_rows) {
    std::swap(*out, fused_pending_);
    return;
  }
  const auto move_some = [&](std::unordered_set<fusion::ClusterId>* from,
                             std::unordered_set<fusion::ClusterId>* to) {
    for (auto it = from->begin(); it != from->end() && out->size() < max_rows;) {
      to->insert(*it);
      it = from->erase(it);
    }
  };
  move_some(&fused_pending_.lines, &out->lines);
  move_some(&fused_pending_.planes, &out->planes);
}

void MapCore::AbandonQueuedWrites(std::unique_lock<std::mutex>& lock) {
  std::deque<Pending> batches;
  std::deque<std::shared_ptr<WriteJob>> jobs;
  batches.swap(queue_);
  jobs.swap(write_jobs_);
  const size_t fused_rows = fused_pending_.size();
  fused_pending_.clear();
  const Status why = write_health_.status();
  lock.unlock();
  Log(LogLevel::kWarn, "stop_without_flush",
      {{"batches_refused", std::to_string(batches.size())},
       {"writes_refused", std::to_string(jobs.size())},
       {"fused_rows_dropped", std::to_string(fused_rows)},
       {"reason", why.message()},
       {"action", "nothing acknowledged is lost; fused rows are recomputed at the next start"}});
  const Status refused =
      Status::Unavailable("mapd stopped while the database refused writes; resend");
  for (Pending& p : batches) p.done({BatchOutcome::Kind::kRejected, refused});
  for (const std::shared_ptr<WriteJob>& job : jobs) job->done(refused);
  lock.lock();
}

void MapCore::CommitGroup(std::vector<Pending>& group, FusedDelta& fused) {
  std::vector<BatchOutcome> outcomes(group.size());
  std::vector<std::pair<size_t, storage::InsertResult>> to_fuse;  // (index in group, result)
  Status failure;
  uint64_t features_stored = 0, batches_stored = 0;
  int64_t newest_id = last_observation_id_;
  StatusOr<std::unique_ptr<storage::WriteTransaction>> txn = store_->BeginWrite();
  if (!txn.ok()) failure = txn.status();

  // The whole group in one call: a backend with round trips (PostgreSQL)
  // stores it in one.
  std::vector<storage::NewObservation> rows(group.size());
  const int64_t received_ns = UnixNowNs();
  for (size_t i = 0; i < group.size(); ++i) {
    const IngestBatch& b = group[i].batch;
    storage::NewObservation& row = rows[i];
    row.robot = b.robot;
    row.session = b.session;
    row.seq = b.seq;
    row.stamp_ns = b.stamp_ns;
    row.received_ns = received_ns;
    row.frame_kind = b.frame_kind;
    row.features = &b.features;
  }
  StatusOr<std::vector<StatusOr<storage::InsertResult>>> results = Status::Internal("not run");
  if (failure.ok()) {
    results = (*txn)->InsertObservations(rows);
    if (!results.ok()) failure = results.status();
  }
  for (size_t i = 0; i < group.size() && failure.ok(); ++i) {
    const IngestBatch& b = group[i].batch;
    StatusOr<storage::InsertResult>& r = (*results)[i];
    if (!r.ok()) {
      outcomes[i] = {BatchOutcome::Kind::kRejected, r.status()};  // InvalidArgument
      continue;
    }
    {
      std::lock_guard<std::mutex> lock(names_mu_);
      robot_names_[r->frame.robot_id] = b.robot;
    }
    if (!r->stored) {
      outcomes[i] = {BatchOutcome::Kind::kDuplicate, Status::Ok()};
      continue;
    }
    outcomes[i] = {BatchOutcome::Kind::kStored, Status::Ok()};
    newest_id = std::max(newest_id, r->observation_id);
    ++batches_stored;
    features_stored += b.features.lines.size() + b.features.planes.size();
    if (r->frame.tied) to_fuse.emplace_back(i, *r);
  }
  if (failure.ok() && !fused.empty()) failure = WriteFusedDelta(fused, txn->get());
  if (failure.ok()) failure = (*txn)->Commit();
  txn = Status::Ok();  // ends the transaction (rolls back if Commit did not happen)
  failure = UnlessTakenOver(failure);
  write_health_.Record(failure);

  if (!failure.ok()) {
    Log(LogLevel::kError, "group_commit_failed",
        {{"batches", std::to_string(group.size())}, {"error", failure.ToString()}});
    for (BatchOutcome& o : outcomes) {
      if (o.kind == BatchOutcome::Kind::kRejected && !o.status.ok()) continue;
      o = {BatchOutcome::Kind::kRejected,
           Status::Unavailable("the batch could not be stored (" + failure.message() +
                               "); nothing was kept, resend it")};
    }
    // The fused rows were not written either: keep them for the next commit.
    std::lock_guard<std::mutex> lock(queue_mu_);
    fused_pending_.Absorb(fused);
  } else {
    last_observation_id_ = newest_id;  // only once committed: a rolled-back id may be reused
    batches_stored_ += batches_stored;
    features_stored_ += features_stored;
    commits_ += 1;
    RecordRate();
    if (!to_fuse.empty()) {
      // Handed to the fuser BEFORE the acks go out, so that a query sent after
      // an ack waits for that batch to be fused (read-your-writes).
      std::lock_guard<std::mutex> lock(fuse_mu_);
      for (auto& [index, result] : to_fuse) {
        ToFuse t;
        t.observation_id = result.observation_id;
        t.robot_id = result.frame.robot_id;
        t.robot = group[index].batch.robot;
        fusion_share_.Committed(t.robot);
        t.T_map_frame = result.frame.T_map_frame;
        t.features = std::move(group[index].batch.features);
        fuse_queue_.push_back(std::move(t));
      }
      committed_count_ += to_fuse.size();
      fuse_cv_.notify_all();
    }
  }
  const auto acked = Clock::now();
  for (size_t i = 0; i < group.size(); ++i) {
    if (outcomes[i].kind == BatchOutcome::Kind::kStored)
      ack_latency_.Record(std::chrono::duration<double>(acked - group[i].queued).count());
    group[i].done(outcomes[i]);
  }
}

void MapCore::HoldFuserForTest() {
  if (!options_.hold_fuser_for_test) return;
  std::unique_lock<std::mutex> lock(fuse_mu_);
  while (!fuser_stopping_ && options_.hold_fuser_for_test())
    fuse_cv_.wait_for(lock, std::chrono::milliseconds(5));
}

void MapCore::ParkFuser() {
  std::unique_lock<std::mutex> lock(fuse_mu_);
  fuse_cv_.wait(lock, [this] { return fuser_stopping_; });
}

void MapCore::FuserLoop() {
  std::deque<ToFuse> work;
  for (;;) {
    HoldFuserForTest();
    {
      std::unique_lock<std::mutex> lock(fuse_mu_);
      // Wakes at least once a second when idle, so that snapshot.max_age_s
      // holds when ingest stops.
      if (!fuse_cv_.wait_for(lock, std::chrono::seconds(1),
                             [this] { return !fuse_queue_.empty() || fuser_stopping_; })) {
        lock.unlock();
        MaybeSnapshot(false);
        continue;
      }
      if (fuser_stopping_) break;  // unfused work stays committed (Stop)
      const size_t take = std::min(fuse_queue_.size(), kMaxObservationsPerFuseRound);
      const auto end = fuse_queue_.begin() + static_cast<std::ptrdiff_t>(take);
      work.assign(std::make_move_iterator(fuse_queue_.begin()), std::make_move_iterator(end));
      fuse_queue_.erase(fuse_queue_.begin(), end);
    }
    FusedDelta delta;
    size_t done = 0;
    for (const ToFuse& t : work) {
      if (fuser_abandon_.load()) break;  // Stop(): the rest is replayed at the next start
      ++done;
      if (!t.tied_sessions.empty()) {
        if (!FuseTiedSessions(t, &delta)) {
          // Stop() came in the middle: the engine holds part of the tie. No
          // snapshot may be taken of it; the next start replays the tie from
          // the snapshot before.
          partial_tie_ = true;
          --done;
          break;
        }
        fused_tie_seq_ = std::max(fused_tie_seq_, t.tie_seq);
        fused_through_id_ = std::max(fused_through_id_, t.tied_through_id);
        continue;
      }
      // Locked per observation, so queries never wait for a whole backlog.
      // What the observation cost the fuser, for FusionShare, measured for a
      // random quarter of them: the thread's CPU clock is a system call (no
      // vDSO), and read twice per observation it took 6 % of the fuser's time
      // in the city soak. Random, so that no robot can send its costly
      // observations where they are not measured.
      const bool measured = (cost_sampler_() & 3) == 0;
      const double cpu_before_s = measured ? ThreadCpuSeconds() : 0.0;
      {
        std::unique_lock<std::shared_mutex> lock(engine_mu_);
        Fuse(t.features, t.observation_id, t.robot_id, t.T_map_frame, &delta);
        ++map_version_;
      }
      fusion_share_.Fused(t.robot, measured
                                       ? std::optional<double>(ThreadCpuSeconds() - cpu_before_s)
                                       : std::nullopt);
      fused_through_id_ = std::max(fused_through_id_, t.observation_id);
      ++fused_since_snapshot_;
    }
    if (done > 0) PublishChange(delta);
    if (!delta.empty()) {
      std::lock_guard<std::mutex> lock(queue_mu_);
      fused_pending_.Absorb(delta);
      queue_cv_.notify_one();
    }
    {
      std::lock_guard<std::mutex> lock(fuse_mu_);
      fused_count_ += done;
    }
    fuse_cv_.notify_all();
    work.clear();
    if (partial_tie_) break;  // (see above) and no snapshot
    MaybeSnapshot(false);
  }
}

void MapCore::PublishChange(const FusedDelta& delta) {
  auto change = std::make_shared<MapChange>();
  // Only this thread changes the engines and the version: both are as of now.
  change->to_version = map_version_.load();
  // Consecutive changes are contiguous: a resumed watch tells from
  // from_version whether a change predates what its client holds.
  change->from_version = published_version_.exchange(change->to_version);
  if (!delta.empty() && watch_hub_.wanted()) {
    std::vector<fusion::FusedFeature> lines;
    std::vector<fusion::FusedPlane> planes;
    {
      std::shared_lock<std::shared_mutex> lock(engine_mu_);
      for (fusion::ClusterId id : delta.lines) {
        std::optional<fusion::FusedFeature> f = engine_->GetPublished(id);
        if (f && f->support >= options_.fusion.min_support) {
          lines.push_back(std::move(*f));
        } else {
          change->lines_gone.push_back(id);
        }
      }
      for (fusion::ClusterId id : delta.planes) {
        std::optional<fusion::FusedPlane> p = plane_engine_->Get(id);
        if (p && p->id == id && p->support >= options_.planes.min_support) {
          planes.push_back(std::move(*p));
        } else {
          change->planes_gone.push_back(id);
        }
      }
    }
    for (fusion::FusedFeature& f : lines) {
      FusedView v;
      v.kind = f.plane_members > 0 ? KindFilter::kPlane : KindFilter::kLine;
      v.robots = RobotNames(f.robots);
      v.feature = std::move(f);
      change->lines.push_back(std::move(v));
    }
    for (fusion::FusedPlane& p : planes) {
      PlaneView v;
      v.robots = RobotNames(p.robots);
      v.plane = std::move(p);
      change->planes.push_back(std::move(v));
    }
  }
  watch_hub_.Publish(std::move(change));
}

Status MapCore::WriteFusedDelta(const FusedDelta& delta, storage::WriteTransaction* txn) {
  std::vector<storage::FusedRow> upserts;
  std::vector<fusion::ClusterId> deletes;
  std::vector<storage::FusedPlaneRow> plane_upserts;
  std::vector<fusion::ClusterId> plane_deletes;
  {
    std::shared_lock<std::shared_mutex> lock(engine_mu_);
    for (fusion::ClusterId id : delta.lines) {
      std::optional<fusion::FusedFeature> f = engine_->GetPublished(id);
      if (f && f->support >= options_.fusion.min_support) {
        upserts.push_back(ToRow(*f));
      } else {
        deletes.push_back(id);
      }
    }
    for (fusion::ClusterId id : delta.planes) {
      std::optional<fusion::FusedPlane> p = plane_engine_->Get(id);
      if (p && p->id == id && p->support >= options_.planes.min_support) {
        plane_upserts.push_back(ToPlaneRow(*p));
      } else {
        plane_deletes.push_back(id);
      }
    }
  }
  // Each list at once: a backend with round trips (PostgreSQL) writes it in one.
  MAPD_RETURN_IF_ERROR(txn->WriteFused(upserts, {deletes.begin(), deletes.end()}));
  return txn->WriteFusedPlanes(plane_upserts, {plane_deletes.begin(), plane_deletes.end()});
}

void MapCore::WaitForFuser(std::chrono::duration<double> timeout) const {
  std::unique_lock<std::mutex> lock(fuse_mu_);
  const uint64_t target = committed_count_;
  fuse_cv_.wait_for(lock, timeout, [&] { return fused_count_ >= target || fuser_stopping_; });
}

void MapCore::Fuse(const geometry::SensorObservation& features, int64_t observation_id,
                   int64_t robot_id, const geometry::Rigid3& T_map_frame, FusedDelta* delta) {
  const fusion::FeatureId first_id = static_cast<fusion::FeatureId>(observation_id)
                                     << kFeatureIdBits;
  StatusOr<fusion::ProjectedObservation> projected =
      fusion::ProjectToGround(features, T_map_frame, first_id, options_.fusion);
  Status s = projected.status();
  fusion::ChangeFeed feed;
  fusion::PlaneChangeFeed plane_feed;
  if (s.ok() && !projected->ground.empty()) {
    s = engine_->AddFrom(static_cast<fusion::ObservationId>(observation_id),
                         static_cast<fusion::RobotId>(robot_id), projected->sensor_xy_m,
                         projected->ground, delta ? &feed : nullptr);
  }
  // Lines and planes are separate engines: a refused plane set leaves the
  // lines fused (and the other way round); both are logged.
  Status planes = Status::Ok();
  if (projected.ok() && !projected->other_planes.empty()) {
    planes = plane_engine_->Add(static_cast<fusion::ObservationId>(observation_id),
                                static_cast<fusion::RobotId>(robot_id), projected->other_planes,
                                delta ? &plane_feed : nullptr);
    if (!planes.ok()) {
      Log(LogLevel::kWarn, "plane_fusion_refused",
          {{"observation", std::to_string(observation_id)}, {"error", planes.ToString()}});
    } else if (delta) {
      Accumulate(plane_feed, &delta->planes);
    }
  }
  if (!s.ok()) {
    // Stored raw but not fused: the data stays, and a rebuild with other
    // parameters may use it. Never seen with validated input.
    Log(LogLevel::kWarn, "fusion_refused",
        {{"observation", std::to_string(observation_id)}, {"error", s.ToString()}});
    return;
  }
  if (delta) Accumulate(feed, &delta->lines);
}

storage::FusedRow MapCore::ToRow(const fusion::FusedFeature& f) const {
  storage::FusedRow row;
  row.id = f.id;
  row.kind = f.plane_members > 0 ? 2 : 1;
  row.segment = f.segment;
  row.z_min_m = f.z_min_m;
  row.z_max_m = f.z_max_m;
  row.support = f.support;
  row.member_count = f.member_count;
  row.robots = RobotList(f.robots);
  return row;
}

storage::FusedPlaneRow MapCore::ToPlaneRow(const fusion::FusedPlane& f) const {
  storage::FusedPlaneRow row;
  row.id = f.id;
  row.normal = f.normal;
  row.offset_m = f.offset_m;
  row.boundary = f.boundary;
  row.area_m2 = f.area_m2;
  row.z_min_m = f.z_min_m;
  row.z_max_m = f.z_max_m;
  row.support = f.support;
  row.member_count = f.member_count;
  row.robots = RobotList(f.robots);
  return row;
}

std::string MapCore::RobotList(const std::vector<fusion::RobotId>& ids) const {
  std::string list;
  for (const std::string& name : RobotNames(ids)) {
    if (!list.empty()) list += ',';
    list += name;
  }
  return list;
}

std::vector<std::string> MapCore::RobotNames(const std::vector<fusion::RobotId>& ids) const {
  std::vector<std::string> names;
  names.reserve(ids.size());
  std::lock_guard<std::mutex> lock(names_mu_);
  for (fusion::RobotId id : ids) {
    auto it = robot_names_.find(static_cast<int64_t>(id));
    names.push_back(it == robot_names_.end() ? "robot-" + std::to_string(id) : it->second);
  }
  std::sort(names.begin(), names.end());
  return names;
}

uint64_t MapCore::FusionBacklog() const {
  std::lock_guard<std::mutex> lock(fuse_mu_);
  return committed_count_ - fused_count_;
}

std::vector<FusedView> MapCore::QueryFeatures(const FeatureQuery& query, uint64_t* map_version,
                                              std::vector<PlaneView>* planes) const {
  WaitForFuser(std::chrono::duration<double>(query.max_wait_s >= 0 ? query.max_wait_s
                                                                   : options_.max_query_wait_s));
  const uint32_t min_support = std::max(query.min_support, options_.fusion.min_support);
  std::vector<fusion::FusedFeature> published;
  std::vector<fusion::FusedPlane> published_planes;
  {
    std::shared_lock<std::shared_mutex> lock(engine_mu_);
    published = engine_->Published();
    if (planes && query.kind != KindFilter::kLine) published_planes = plane_engine_->Published();
    if (map_version) *map_version = map_version_.load();
  }
  if (planes) {
    planes->clear();
    const uint32_t min_plane_support = std::max(query.min_support, options_.planes.min_support);
    for (fusion::FusedPlane& p : published_planes) {
      if (p.support < min_plane_support) continue;
      if (query.bbox && !PolygonMeetsBox(p.boundary, *query.bbox)) continue;
      PlaneView v;
      v.robots = RobotNames(p.robots);
      v.plane = std::move(p);
      planes->push_back(std::move(v));
    }
  }
  std::vector<FusedView> out;
  for (fusion::FusedFeature& f : published) {
    if (f.support < min_support) continue;
    const KindFilter kind = f.plane_members > 0 ? KindFilter::kPlane : KindFilter::kLine;
    if (query.kind != KindFilter::kAny && query.kind != kind) continue;
    if (query.bbox && !geometry::Intersects(f.segment, *query.bbox)) continue;
    FusedView v;
    v.robots = RobotNames(f.robots);
    v.feature = std::move(f);
    v.kind = kind;
    out.push_back(std::move(v));
  }
  return out;
}

void MapCore::RecordRate() {
  const auto now = Clock::now();
  std::lock_guard<std::mutex> lock(rate_mu_);
  if (!rate_samples_.empty() && now - rate_samples_.back().t < std::chrono::milliseconds(250)) {
    // Keep the newest counts (else commits after the last sample would show
    // as a rate forever once ingest stops).
    rate_samples_.back().batches = batches_stored_.load();
    rate_samples_.back().features = features_stored_.load();
    return;
  }
  rate_samples_.push_back({now, batches_stored_.load(), features_stored_.load()});
  while (rate_samples_.size() > 2 && now - rate_samples_[1].t > std::chrono::seconds(10)) {
    rate_samples_.pop_front();
  }
}

CoreStats MapCore::Stats() const {
  CoreStats s;
  const auto now = Clock::now();
  s.batches_stored = batches_stored_.load();
  s.features_stored = features_stored_.load();
  s.commits = commits_.load();
  s.uptime_s = std::chrono::duration<double>(now - started_).count();
  {
    std::lock_guard<std::mutex> lock(rate_mu_);
    // Rate over the last 10 s (or since the start): what was stored since the
    // newest sample at least 10 s old. Samples are taken only on commits, so
    // with none in the window the base is the newest sample and the rate
    // decays to 0 within 10 s of the last commit (it used to divide by a
    // window that kept growing from an old sample).
    uint64_t base_b = 0, base_f = 0;
    for (const RateSample& r : rate_samples_) {
      if (now - r.t < std::chrono::seconds(10)) break;
      base_b = r.batches;
      base_f = r.features;
    }
    const double window =
        std::max(1e-3, std::min(10.0, std::chrono::duration<double>(now - started_).count()));
    s.batches_per_s = static_cast<double>(s.batches_stored - base_b) / window;
    s.features_per_s = static_cast<double>(s.features_stored - base_f) / window;
  }
  {
    std::lock_guard<std::mutex> lock(fuse_mu_);
    s.fusion_backlog = committed_count_ - fused_count_;
  }
  s.fusion_share_refused = fusion_share_.refused_total();
  for (const FusionShare::RobotShare& r : fusion_share_.Shares()) {
    s.fusion_shares.push_back({r.robot, r.pending, r.cost_per_obs_s, r.refused});
  }
  s.ack_latency = ack_latency_.Snapshot();
  s.recovering = !ready_.load();
  s.replaying = replaying_.load();
  if (Status w = write_health_.status(); !w.ok()) s.write_failure = w.message();
  s.replay_length = fused_since_snapshot_.load();
  if (const int64_t created = snapshot_created_ns_.load(); created > 0) {
    s.snapshot_age_s = static_cast<double>(UnixNowNs() - created) * 1e-9;
  }
  std::shared_lock<std::shared_mutex> lock(engine_mu_);
  s.fused_features = engine_->published_count();
  s.fused_raw_features = engine_->feature_count();
  s.fusion_nodes = engine_->node_count();
  s.clusters = engine_->cluster_count();
  s.retired_walls = engine_->retired_count();
  s.fused_planes = plane_engine_->published_count();
  s.plane_nodes = plane_engine_->node_count();
  s.map_version = map_version_.load();
  return s;
}

}  // namespace mapd::service
