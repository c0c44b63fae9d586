// MapCore's fusion state across restarts: recovery at start (newest snapshot,
// then a replay of what came after it, in the live order), ties of session
// frames, and periodic snapshots. See map_core.h.
//
// The live order. The fuser takes committed observations in commit (= id)
// order; an observation of a session that is not tied yet is stored but not
// fused. A transaction that ties sessions is recorded at its place in that
// order (sessions.tied_through_observation T = the newest observation id
// committed before it, sessions.tie_seq = 1, 2, ... per transaction); the
// fuser then fuses the tied sessions' stored observations up to T, in id
// order. So the engine's history is a function of the database alone, and a
// replay from any snapshot (which records the position it reflects) redoes it
// exactly: the bounded engine is deterministic, not order independent.
#include <malloc.h>

#include <algorithm>
#include <map>
#include <mutex>
#include <thread>
#include <utility>

#include "common/clock.h"
#include "service/log.h"
#include "service/map_core.h"

namespace mapd::service {
namespace {

using Clock = std::chrono::steady_clock;

// The first failure among a snapshot's part writes; the parts after it skip.
// The writer runs the parts, but a part refused at a stop is told on the
// thread that submitted it.
class FirstFailure {
 public:
  void Record(const Status& s) {
    std::lock_guard<std::mutex> lock(mu_);
    if (!s.ok() && status_.ok()) status_ = s;
  }
  Status Get() const {
    std::lock_guard<std::mutex> lock(mu_);
    return status_;
  }

 private:
  mutable std::mutex mu_;
  Status status_;  // GUARDED_BY(mu_)
};

int64_t MsSince(Clock::time_point t0) {
  return std::chrono::duration_cast<std::chrono::milliseconds>(Clock::now() - t0).count();
}

bool SamePlaneRow(const storage::FusedPlaneRow& a, const storage::FusedPlaneRow& b) {
  return a.id == b.id && a.normal == b.normal && a.offset_m == b.offset_m &&
         a.boundary == b.boundary && a.area_m2 == b.area_m2 && a.z_min_m == b.z_min_m &&
         a.z_max_m == b.z_max_m && a.support == b.support && a.member_count == b.member_count &&
         a.robots == b.robots;
}

bool SameFusedRow(const storage::FusedRow& a, const storage::FusedRow& b) {
  return a.id == b.id && a.kind == b.kind && a.segment.a == b.segment.a &&
         a.segment.b == b.segment.b && a.z_min_m == b.z_min_m && a.z_max_m == b.z_max_m &&
         a.support == b.support && a.member_count == b.member_count && a.robots == b.robots;
}

// Snapshots kept in the database: the newest, and one before it in case the
// newest cannot be used.
constexpr int kSnapshotsKept = 2;
constexpr auto kProgressEvery = std::chrono::seconds(2);
// A serving replay publishes a round every this many observations: the
// change feed and the fused table move on, readers waiting are woken.
constexpr uint64_t kReplayRound = 256;

}  // namespace

bool MapCore::Recover() {
  const auto t0 = Clock::now();
  std::string from = "scratch";
  bool had_snapshot = false;
  // The newest snapshot, else the one before it (raw retention keeps what
  // either needs), else a replay of every stored observation.
  for (int skip = 0; skip < kSnapshotsKept && from == "scratch" &&
                     options_.fusion.mode == fusion::FusionMode::kBounded;
       ++skip) {
    StatusOr<storage::FusionSnapshot> snap = store_->LatestSnapshot(skip);
    if (snap.ok()) {
      had_snapshot = true;
      StatusOr<std::unique_ptr<fusion::FusionEngine>> loaded =
          fusion::FusionEngine::LoadState(options_.fusion, snap->state);
      // Both engines come from the same snapshot, or neither does: a snapshot
      // from before plane fusion (schema 5) is replayed past once.
      StatusOr<std::unique_ptr<fusion::PlaneFusionEngine>> loaded_planes =
          snap->has_plane_state
              ? fusion::PlaneFusionEngine::LoadState(options_.planes, snap->plane_state)
              : StatusOr<std::unique_ptr<fusion::PlaneFusionEngine>>(
                    Status::FailedPrecondition("the snapshot predates plane fusion"));
      if (loaded.ok() && !loaded_planes.ok()) loaded = loaded_planes.status();
      if (loaded.ok()) {
        std::unique_lock<std::shared_mutex> lock(engine_mu_);
        engine_ = std::move(loaded).value();
        plane_engine_ = std::move(loaded_planes).value();
        map_version_ = snap->map_version;
        fused_through_id_ = snap->through_observation;
        fused_tie_seq_ = snap->through_tie_seq;
        snapshot_created_ns_ = snap->created_ns;
        from = "snapshot";
      } else {
        Log(LogLevel::kWarn, "snapshot_unusable",
            {{"snapshot", std::to_string(snap->id)},
             {"error", loaded.status().ToString()},
             {"action", skip + 1 < kSnapshotsKept ? "trying the one before"
                                                  : "replaying every stored observation"}});
      }
    } else if (snap.status().code() == StatusCode::kNotFound) {
      break;
    } else {
      // E.g. a part of it missing: the one before may still be whole.
      had_snapshot = true;
      Log(LogLevel::kWarn, "snapshot_unreadable",
          {{"error", snap.status().ToString()},
           {"action", skip + 1 < kSnapshotsKept ? "trying the one before"
                                                : "replaying every stored observation"}});
    }
  }
  // Retention may have dropped what only the unusable snapshots reflected.
  if (from == "scratch" && had_snapshot && options_.raw_retention_days > 0) {
    Log(LogLevel::kWarn, "replaying_retained_observations_only",
        {{"raw_retention_days", std::to_string(options_.raw_retention_days)},
         {"consequence", "walls seen only by dropped observations are missing from the map"}});
  }
  StatusOr<ReplayPlan> plan = PlanReplay();
  Status s = plan.status();
  // After a snapshot, mapd serves at once: the observations after it are a
  // fusion backlog like any other (reads wait for it up to limits.read_wait_s,
  // the writer's backpressure counts it, the change feed and the fused table
  // follow it). Without one (a first start, exact mode, an unusable
  // snapshot) the replay can be the whole history, and mapd serves after it.
  const bool serve_first = s.ok() && from == "snapshot";
  uint64_t counted = 0;  // of the replay, in committed_count_
  if (serve_first) {
    counted = plan->newest > fused_through_id_
                  ? static_cast<uint64_t>(plan->newest - fused_through_id_)
                  : 0;
    {
      std::lock_guard<std::mutex> lock(fuse_mu_);
      committed_count_ += counted;
    }
    replaying_ = true;
    MarkReady(Status::Ok());
    Log(LogLevel::kInfo, "serving_while_replaying",
        {{"from", from},
         {"to_replay_at_most", std::to_string(counted)},
         {"map_version", std::to_string(map_version_.load())},
         {"ms", std::to_string(MsSince(t0))}});
  }
  if (s.ok()) s = Replay(std::move(plan).value(), serve_first ? &counted : nullptr);
  if (serve_first) {
    std::lock_guard<std::mutex> lock(fuse_mu_);
    fused_count_ += counted;  // what the id range over-counted (gaps)
  }
  fuse_cv_.notify_all();
  if (s.ok()) s = QueueFusedTableSync();
  last_snapshot_ = Clock::now();
  if (s.ok()) {
    std::shared_lock<std::shared_mutex> lock(engine_mu_);
    Log(LogLevel::kInfo, "map_recovered",
        {{"from", from},
         {"replayed", std::to_string(recovery_replayed_.load())},
         {"raw_features", std::to_string(engine_->feature_count())},
         {"nodes", std::to_string(engine_->node_count())},
         {"fused", std::to_string(engine_->published_count())},
         {"fused_planes", std::to_string(plane_engine_->published_count())},
         {"map_version", std::to_string(map_version_.load())},
         {"ms", std::to_string(MsSince(t0))}});
  } else if (!cancel_recovery_.load()) {
    Log(LogLevel::kError, "map_recovery_failed", {{"error", s.ToString()}});
  }
  if (serve_first) {
    replaying_ = false;
    // A replay that failed, or that Stop() cut short, leaves the engine
    // behind the database: nothing more may be fused onto it or snapshotted
    // (the next start replays again), and requests get the error.
    if (!s.ok()) {
      std::lock_guard<std::mutex> lock(ready_mu_);
      recovery_status_ =
          cancel_recovery_.load()
              ? Status::Unavailable("mapd is shutting down")
              : Status::Internal("mapd could not recover its fused map: " + s.message());
    }
    return s.ok();
  }
  MarkReady(s);
  return s.ok();
}

void MapCore::MarkReady(const Status& s) {
  std::vector<std::function<void()>> callbacks;
  {
    std::lock_guard<std::mutex> lock(ready_mu_);
    recovery_status_ =
        s.ok() ? Status::Ok()
               : Status::Internal("mapd could not recover its fused map: " + s.message());
    // The change feed starts here: the history begins at the recovered
    // version, so a watch from before the restart gets a resync.
    if (s.ok()) {
      published_version_ = map_version_.load();
      watch_hub_.Start(published_version_);
    }
    ready_ = true;
    callbacks.swap(on_ready_);
  }
  ready_cv_.notify_all();
  if (s.ok()) {
    for (auto& fn : callbacks) fn();
  }
}

StatusOr<MapCore::ReplayPlan> MapCore::PlanReplay() {
  ReplayPlan plan;
  StatusOr<std::vector<storage::SessionFrame>> sessions = store_->ListSessions();
  if (!sessions.ok()) return sessions.status();
  plan.sessions = std::move(sessions).value();
  StatusOr<int64_t> newest = store_->NewestObservationId();
  if (!newest.ok()) return newest.status();
  plan.newest = *newest;
  recovery_target_id_ = *newest;
  // Sessions fused as their observations come (tied at or before the engine's
  // position), and the ties still to replay, in the live order.
  for (const storage::SessionFrame& f : plan.sessions) {
    if (!f.tied) continue;
    if (f.tie_seq <= fused_tie_seq_) {
      plan.streaming[f.session_id] = f.T_map_frame;
    } else {
      plan.ties[{f.tied_through_observation, f.tie_seq}].push_back(f.session_id);
    }
  }
  return plan;
}

Status MapCore::Replay(ReplayPlan plan, uint64_t* counted) {
  const std::vector<storage::SessionFrame>& sessions = plan.sessions;
  std::unordered_map<int64_t, geometry::Rigid3>& streaming = plan.streaming;
  const int64_t newest = plan.newest;
  auto last_log = Clock::now();
  const auto t0 = last_log;
  // Serving (counted != null): rounds as the fuser's, so that readers, the
  // change feed and the fused table follow the replay.
  FusedDelta delta;
  uint64_t in_round = 0;
  const auto end_round = [&] {
    PublishChange(delta);
    if (!delta.empty()) {
      std::lock_guard<std::mutex> lock(queue_mu_);
      fused_pending_.Absorb(delta);
      queue_cv_.notify_one();
    }
    delta = FusedDelta();
    {
      std::lock_guard<std::mutex> lock(fuse_mu_);
      const uint64_t n = std::min(in_round, *counted);
      fused_count_ += n;
      *counted -= n;
    }
    fuse_cv_.notify_all();
    in_round = 0;
  };
  const auto fuse = [&](const storage::StoredObservation& obs, const geometry::Rigid3& T) {
    while (counted != nullptr && options_.hold_replay_for_test && options_.hold_replay_for_test() &&
           !cancel_recovery_.load()) {
      std::this_thread::sleep_for(std::chrono::milliseconds(2));
    }
    if (cancel_recovery_.load()) return Status::Unavailable("recovery cancelled: mapd is stopping");
    {
      std::unique_lock<std::shared_mutex> lock(engine_mu_);
      Fuse(obs.features, obs.id, obs.robot_id, T, counted != nullptr ? &delta : nullptr);
      ++map_version_;
    }
    ++fused_since_snapshot_;
    if (counted != nullptr && ++in_round == kReplayRound) end_round();
    const uint64_t done = ++recovery_replayed_;
    if (Clock::now() - last_log >= kProgressEvery) {
      last_log = Clock::now();
      const double s = std::chrono::duration<double>(last_log - t0).count();
      Log(LogLevel::kInfo, "recovering",
          {{"replayed", std::to_string(done)},
           {"at_id", std::to_string(obs.id)},
           {"newest_id", std::to_string(newest)},
           {"per_s", std::to_string(static_cast<int64_t>(static_cast<double>(done) / s))}});
    }
    return Status::Ok();
  };
  const auto stream_until = [&](int64_t through_id) {
    if (through_id <= fused_through_id_) return Status::Ok();
    Status s = store_->ForEachObservationBetween(
        fused_through_id_, through_id, [&](const storage::StoredObservation& obs) {
          auto frame = streaming.find(obs.session_id);
          return frame == streaming.end() ? Status::Ok() : fuse(obs, frame->second);
        });
    if (s.ok()) fused_through_id_ = through_id;
    return s;
  };
  Status s = Status::Ok();
  for (const auto& [at, tied] : plan.ties) {
    s = stream_until(at.first);
    if (!s.ok()) break;
    std::unordered_map<int64_t, geometry::Rigid3> frames;
    for (const storage::SessionFrame& f : sessions) {
      if (std::find(tied.begin(), tied.end(), f.session_id) != tied.end())
        frames[f.session_id] = f.T_map_frame;
    }
    s = store_->ForEachObservationOfSessions(
        tied, at.first,
        [&](const storage::StoredObservation& obs) { return fuse(obs, frames[obs.session_id]); });
    if (!s.ok()) break;
    streaming.insert(frames.begin(), frames.end());
    fused_tie_seq_ = at.second;
  }
  if (s.ok()) s = stream_until(newest);
  if (counted != nullptr && in_round > 0) end_round();
  return s;
}

Status MapCore::QueueFusedTableSync() {
  StatusOr<std::vector<storage::FusedRow>> stored = store_->LoadFused();
  if (!stored.ok()) return stored.status();
  std::unordered_map<uint64_t, storage::FusedRow> old_rows;
  for (auto& r : *stored) old_rows.emplace(r.id, std::move(r));
  FusedDelta delta;
  {
    std::shared_lock<std::shared_mutex> lock(engine_mu_);
    for (const fusion::FusedFeature& f : engine_->Published()) {
      const storage::FusedRow row = ToRow(f);
      auto it = old_rows.find(row.id);
      if (it == old_rows.end() || !SameFusedRow(it->second, row)) delta.lines.insert(f.id);
      if (it != old_rows.end()) old_rows.erase(it);
    }
  }
  for (const auto& [id, row] : old_rows)
    delta.lines.insert(id);  // gone: WriteFusedDelta deletes it
  StatusOr<std::vector<storage::FusedPlaneRow>> stored_planes = store_->LoadFusedPlanes();
  if (!stored_planes.ok()) return stored_planes.status();
  std::unordered_map<uint64_t, storage::FusedPlaneRow> old_planes;
  for (auto& r : *stored_planes) old_planes.emplace(r.id, std::move(r));
  {
    std::shared_lock<std::shared_mutex> lock(engine_mu_);
    for (const fusion::FusedPlane& p : plane_engine_->Published()) {
      const storage::FusedPlaneRow row = ToPlaneRow(p);
      auto it = old_planes.find(row.id);
      if (it == old_planes.end() || !SamePlaneRow(it->second, row)) delta.planes.insert(p.id);
      if (it != old_planes.end()) old_planes.erase(it);
    }
  }
  for (const auto& [id, row] : old_planes) delta.planes.insert(id);
  if (!delta.empty()) {
    Log(LogLevel::kInfo, "fused_table_sync", {{"rows", std::to_string(delta.size())}});
    std::lock_guard<std::mutex> lock(queue_mu_);
    fused_pending_.Absorb(delta);
    queue_cv_.notify_one();
  }
  return Status::Ok();
}

bool MapCore::FuseTiedSessions(const ToFuse& tie, FusedDelta* delta) {
  const auto t0 = Clock::now();
  std::unordered_map<int64_t, geometry::Rigid3> frames;
  for (int64_t id : tie.tied_sessions) {
    StatusOr<storage::SessionFrame> frame = store_->GetSession(id);
    if (frame.ok() && frame->tied) frames[id] = frame->T_map_frame;
  }
  uint64_t added = 0;
  bool interrupted = false;
  Status s = store_->ForEachObservationOfSessions(
      tie.tied_sessions, tie.tied_through_id, [&](const storage::StoredObservation& obs) {
        // A tie can hold millions of observations: a stop does not wait for it.
        if (fuser_abandon_.load()) {
          interrupted = true;
          return Status::Unavailable("mapd is stopping");
        }
        auto frame = frames.find(obs.session_id);
        if (frame == frames.end()) return Status::Ok();
        // Locked per observation, so queries never wait for a whole session.
        std::unique_lock<std::shared_mutex> lock(engine_mu_);
        Fuse(obs.features, obs.id, obs.robot_id, frame->second, delta);
        ++map_version_;
        ++added;
        return Status::Ok();
      });
  fused_since_snapshot_ += added;
  if (interrupted) {
    Log(LogLevel::kInfo, "tied_sessions_fusion_interrupted",
        {{"observations_fused", std::to_string(added)}, {"action", "replayed at the next start"}});
    return false;
  }
  if (!s.ok()) {
    // The ties are committed, so the next start fuses these sessions; until
    // then the map lacks what was not read. Never seen unless storage fails.
    Log(LogLevel::kError, "tied_sessions_fusion_failed", {{"error", s.ToString()}});
  }
  Log(LogLevel::kInfo, "tied_sessions_fused",
      {{"sessions", std::to_string(tie.tied_sessions.size())},
       {"observations", std::to_string(added)},
       {"ms", std::to_string(MsSince(t0))}});
  return true;
}

void MapCore::MaybeSnapshot(bool force) {
  if (options_.fusion.mode != fusion::FusionMode::kBounded) return;
  if (options_.snapshot_every_observations == 0 || fused_since_snapshot_.load() == 0) return;
  const bool due =
      fused_since_snapshot_.load() >= options_.snapshot_every_observations ||
      Clock::now() - last_snapshot_ >= std::chrono::duration<double>(options_.snapshot_max_age_s);
  if (!force && (!due || snapshot_in_flight_.load())) return;
  const auto t0 = Clock::now();
  storage::FusionSnapshot snap;
  snap.created_ns = UnixNowNs();
  snap.map_version = map_version_.load();
  snap.through_observation = fused_through_id_;
  snap.through_tie_seq = fused_tie_seq_;
  snap.params = fusion::FusionParamsKey(options_.fusion);
  if (!force) {
    std::lock_guard<std::mutex> lock(snapshot_spare_mu_);
    snap.state.swap(snapshot_spare_);  // SaveState clears it, keeping its memory
  }
  {
    // This thread is the engine's only writer: a shared lock is enough.
    std::shared_lock<std::shared_mutex> lock(engine_mu_);
    Status saved = engine_->SaveState(&snap.state);
    if (saved.ok()) saved = plane_engine_->SaveState(&snap.plane_state);
    snap.has_plane_state = saved.ok();
    if (!saved.ok()) {
      Log(LogLevel::kError, "snapshot_failed", {{"error", saved.ToString()}});
      return;
    }
  }
  const int64_t encode_ms = MsSince(t0);
  const uint64_t covered = fused_since_snapshot_.exchange(0);
#ifdef __GLIBC__
  // The fuse queue and gRPC buffers of a burst are freed by now; glibc keeps
  // freed memory in its arenas unless asked, and RSS should follow the map.
  malloc_trim(0);
#endif
  last_snapshot_ = Clock::now();
  const size_t bytes = snap.state.size();
  const int64_t created_ns = snap.created_ns;
  auto shared = std::make_shared<storage::FusionSnapshot>(std::move(snap));
  const auto done = [this, shared, bytes, created_ns, encode_ms, covered, t0](const Status& s) {
    {
      // Every write that reads the bytes has run: they serve the next snapshot.
      std::lock_guard<std::mutex> lock(snapshot_spare_mu_);
      snapshot_spare_.swap(shared->state);
    }
    if (!s.ok()) {
      snapshot_in_flight_ = false;
      // Still to replay after a restart; the next snapshot is due at once.
      fused_since_snapshot_ += covered;
      // Unavailable: mapd is stopping, and Stop() writes a snapshot itself.
      if (s.code() != StatusCode::kUnavailable) {
        Log(LogLevel::kWarn, "snapshot_write_failed", {{"error", s.ToString()}});
      }
      return;
    }
    snapshot_created_ns_ = created_ns;
    Log(LogLevel::kInfo, "snapshot_written",
        {{"bytes", std::to_string(bytes)},
         {"encode_ms", std::to_string(encode_ms)},
         {"ms", std::to_string(MsSince(t0))}});
    DropUnusedSnapshotParts();  // then retention, and the next snapshot may begin
  };
  if (force) {  // Stop(): the writer is gone, this thread writes, in one commit
    StatusOr<std::unique_ptr<storage::WriteTransaction>> txn = store_->BeginWrite();
    Status s = txn.ok() ? (*txn)->InsertSnapshot(*shared, kSnapshotsKept) : txn.status();
    if (s.ok()) s = (*txn)->Commit();
    done(s);
    return;
  }
  // In parts, each committed on its own between the batches' commits; the
  // snapshot's row, written last, makes it one. A part that fails ends the
  // rest (they are then deleted after the next snapshot).
  snapshot_in_flight_ = true;
  const std::vector<std::string_view> parts =
      storage::SnapshotPartsOf(*shared, options_.snapshot_part_bytes);
  const storage::SnapshotParts where{created_ns, static_cast<int>(parts.size())};
  auto failed = std::make_shared<FirstFailure>();
  for (size_t i = 0; i < parts.size(); ++i) {
    SubmitBackgroundWrite(
        [shared, failed, key = where.key, index = static_cast<int>(i),
         part = parts[i]](storage::WriteTransaction* txn) {
          if (Status before = failed->Get(); !before.ok()) return before;
          return txn->InsertSnapshotPart(key, index, part);
        },
        [failed](const Status& s) { failed->Record(s); });
  }
  SubmitBackgroundWrite(
      [shared, failed, where](storage::WriteTransaction* txn) {
        if (Status before = failed->Get(); !before.ok()) return before;
        return txn->InsertSnapshot(*shared, kSnapshotsKept, where);
      },
      done);
}

// Runs while snapshot_in_flight_ is true, and ends it; then raw retention.
void MapCore::DropUnusedSnapshotParts() {
  constexpr int kPerRound = 8;  // parts (MiB) per transaction: keeps commits short
  auto deleted = std::make_shared<int>(0);
  SubmitBackgroundWrite(
      [deleted](storage::WriteTransaction* txn) {
        StatusOr<int> n = txn->DeleteUnusedSnapshotParts(kPerRound);
        if (!n.ok()) return n.status();
        *deleted = *n;
        return Status::Ok();
      },
      [this, deleted](const Status& s) {
        if (!s.ok() && s.code() != StatusCode::kUnavailable) {
          Log(LogLevel::kWarn, "snapshot_parts_cleanup_failed", {{"error", s.ToString()}});
        }
        if (s.ok() && *deleted == kPerRound) {
          DropUnusedSnapshotParts();  // more to do
          return;
        }
        // Only now: the next snapshot's parts, not named until its row is
        // written, must not be taken for unused ones.
        snapshot_in_flight_ = false;
        // After the parts: its incremental vacuum gives their pages back too.
        if (s.ok() && options_.raw_retention_days > 0) DropExpiredObservations();
      });
}

void MapCore::DropExpiredObservations() {
  constexpr int kPerRound = 50000;  // rows per transaction: keeps commits short
  const int64_t cutoff_ns =
      UnixNowNs() - static_cast<int64_t>(options_.raw_retention_days * 86400.0 * 1e9);
  auto dropped = std::make_shared<uint64_t>(0);
  SubmitBackgroundWrite(
      [cutoff_ns, dropped](storage::WriteTransaction* txn) {
        StatusOr<uint64_t> n = txn->DropRawObservations(cutoff_ns, kPerRound);
        if (!n.ok()) return n.status();
        *dropped = *n;
        return Status::Ok();
      },
      [this, dropped](const Status& s) {
        if (!s.ok()) {
          // Unavailable: mapd is stopping; the next snapshot retries.
          if (s.code() != StatusCode::kUnavailable) {
            Log(LogLevel::kWarn, "raw_retention_failed", {{"error", s.ToString()}});
          }
          return;
        }
        if (*dropped == 0) return;
        Log(LogLevel::kInfo, "raw_retention", {{"dropped_observations", std::to_string(*dropped)}});
        if (*dropped == kPerRound) DropExpiredObservations();  // more to do
      });
}

}  // namespace mapd::service
