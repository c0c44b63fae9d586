#include "storage/sqlite/store.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <sys/statvfs.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstring>

#include "storage/blob_codec.h"
#include "storage/observation_codec.h"
#include "storage/sqlite/pose_columns.h"
#include "storage/sqlite/schema.h"

namespace mapd::storage {
namespace {

uint64_t FileSize(const std::string& path) {
  struct stat st {};
  return stat(path.c_str(), &st) == 0 ? static_cast<uint64_t>(st.st_size) : 0;
}

// Prepares `sql` into *out or returns the error.
Status PrepareInto(sqlite3* db, const char* sql, Statement* out) {
  StatusOr<Statement> s = Statement::Prepare(db, sql);
  if (!s.ok()) return s.status();
  *out = std::move(s).value();
  return Status::Ok();
}

}  // namespace

StatusOr<std::unique_ptr<SqliteStore>> SqliteStore::Open(const std::string& path,
                                                         const StoreOptions& options) {
  std::unique_ptr<SqliteStore> store(new SqliteStore());
  store->path_ = path;
  // A new database is the owner's only (0600) whatever the umask: it holds
  // the token hashes. SQLite gives its -wal and -shm files the same mode. (An
  // empty file is an empty database to SQLite; an existing one is untouched.)
  if (const int fd = open(path.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0600); fd >= 0)
    close(fd);
  StatusOr<DbHandle> writer = OpenDatabase(path, /*read_only=*/false);
  if (!writer.ok()) return writer.status();
  store->writer_ = std::move(writer).value();
  sqlite3* w = store->writer_.get();
  sqlite3_busy_timeout(w, options.busy_timeout_ms);
  // Before anything changes the file (WAL mode does): never another
  // application's database.
  MAPD_RETURN_IF_ERROR(ClaimDatabase(w, path));
  StatusOr<Statement> mode = Statement::Prepare(w, "PRAGMA journal_mode=WAL");
  if (!mode.ok()) return mode.status();
  StatusOr<bool> mode_row = mode->Step();
  if (!mode_row.ok()) return mode_row.status();
  if (mode->ColumnText(0) != "wal") {
    return Status::FailedPrecondition("database '" + path + "' cannot use WAL mode (got " +
                                      mode->ColumnText(0) + "); is it on a network file system?");
  }
  mode = Status::Ok();  // finalize before further statements
  MAPD_RETURN_IF_ERROR(
      Exec(w, options.synchronous_full ? "PRAGMA synchronous=FULL" : "PRAGMA synchronous=NORMAL"));
  // 16 MiB of page cache: inserts touch the tails of the tables and one
  // index leaf per session, and RSS should not grow with the database file.
  MAPD_RETURN_IF_ERROR(Exec(w, "PRAGMA cache_size=-16384; PRAGMA temp_store=MEMORY"));
  if (options.max_db_bytes > 0) {
    // SQLite then answers SQLITE_FULL as on a full disk: one path for both.
    StatusOr<Statement> page = Statement::Prepare(w, "PRAGMA page_size");
    if (!page.ok()) return page.status();
    StatusOr<bool> page_row = page->Step();
    if (!page_row.ok()) return page_row.status();
    const uint64_t pages =
        std::max<uint64_t>(1, options.max_db_bytes / static_cast<uint64_t>(page->ColumnInt(0)));
    page = Status::Ok();
    MAPD_RETURN_IF_ERROR(Exec(w, "PRAGMA max_page_count = " + std::to_string(pages)));
  }
  MAPD_RETURN_IF_ERROR(Migrate(w));

  StatusOr<DbHandle> reader = OpenDatabase(path, /*read_only=*/true);
  if (!reader.ok()) return reader.status();
  store->reader_ = std::move(reader).value();
  MAPD_RETURN_IF_ERROR(store->Prepare());
  return store;
}

SqliteStore::~SqliteStore() {
  if (writer_) (void)Checkpoint();
}

Status SqliteStore::Prepare() {
  sqlite3* w = writer_.get();
  MAPD_RETURN_IF_ERROR(PrepareInto(w, "BEGIN IMMEDIATE", &begin_));
  MAPD_RETURN_IF_ERROR(PrepareInto(w, "COMMIT", &commit_));
  MAPD_RETURN_IF_ERROR(PrepareInto(w, "ROLLBACK", &rollback_));
  MAPD_RETURN_IF_ERROR(
      PrepareInto(w, "INSERT INTO robots (name, first_seen_ns, last_seen_ns) VALUES (?1, ?2, ?2)",
                  &insert_robot_));
  MAPD_RETURN_IF_ERROR(PrepareInto(w,
                                   "INSERT INTO sessions (robot_id, name, created_ns, frame_kind, "
                                   "tied, qw, qx, qy, qz, tx, ty, tz) "
                                   "VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7, ?8, ?9, ?10, ?11, ?12)",
                                   &insert_session_));
  MAPD_RETURN_IF_ERROR(
      PrepareInto(w,
                  "INSERT OR IGNORE INTO observations (session_id, seq, stamp_ns, received_ns, "
                  "qw, qx, qy, qz, tx, ty, tz, line_count, plane_count, payload) "
                  "VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7, ?8, ?9, ?10, ?11, ?12, ?13, ?14)",
                  &insert_obs_));
  MAPD_RETURN_IF_ERROR(
      PrepareInto(w, "SELECT id FROM observations WHERE session_id = ?1 AND seq = ?2", &find_obs_));
  MAPD_RETURN_IF_ERROR(
      PrepareInto(w,
                  "UPDATE robots SET batches = batches + ?2, features = features + ?3, "
                  "last_seen_ns = max(last_seen_ns, ?4) WHERE id = ?1",
                  &update_robot_));
  MAPD_RETURN_IF_ERROR(PrepareInto(
      w,
      "INSERT OR REPLACE INTO fused_features (id, kind, ax, ay, bx, by, z_min, z_max, support, "
      "member_count, robots, updated_ns) VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7, ?8, ?9, ?10, ?11, "
      "?12)",
      &upsert_fused_));
  MAPD_RETURN_IF_ERROR(PrepareInto(w, "DELETE FROM fused_features WHERE id = ?1", &delete_fused_));

  // Warm the caches of robots and sessions.
  StatusOr<Statement> robots = Statement::Prepare(w, "SELECT id, name FROM robots");
  if (!robots.ok()) return robots.status();
  for (;;) {
    StatusOr<bool> row = robots->Step();
    if (!row.ok()) return row.status();
    if (!*row) break;
    robot_ids_[robots->ColumnText(1)] = robots->ColumnInt(0);
    robot_names_[robots->ColumnInt(0)] = robots->ColumnText(1);
  }
  StatusOr<Statement> sessions =
      Statement::Prepare(w,
                         "SELECT id, robot_id, name, frame_kind, tied, qw, qx, qy, qz, tx, ty, tz, "
                         "tied_through_observation, tie_seq FROM sessions");
  if (!sessions.ok()) return sessions.status();
  for (;;) {
    StatusOr<bool> row = sessions->Step();
    if (!row.ok()) return row.status();
    if (!*row) break;
    SessionFrame f;
    f.session_id = sessions->ColumnInt(0);
    f.robot_id = sessions->ColumnInt(1);
    f.name = sessions->ColumnText(2);
    f.kind = static_cast<FrameKind>(sessions->ColumnInt(3));
    f.tied = sessions->ColumnInt(4) != 0;
    if (f.tied) f.T_map_frame = ColumnPose(*sessions, 5);
    f.tied_through_observation = sessions->ColumnInt(12);
    f.tie_seq = sessions->ColumnInt(13);
    max_tie_seq_ = std::max(max_tie_seq_, f.tie_seq);
    sessions_[SessionKey(f.robot_id, sessions->ColumnText(2))] = f;
  }
  return Status::Ok();
}

StatusOr<std::unique_ptr<WriteTransaction>> SqliteStore::BeginWrite() {
  MAPD_RETURN_IF_ERROR(begin_.Run());
  return std::unique_ptr<WriteTransaction>(new SqliteWriteTransaction(this));
}

Status SqliteStore::Checkpoint() {
  // Freed pages (old snapshots, retention) leave the file first.
  MAPD_RETURN_IF_ERROR(Exec(writer_.get(), "PRAGMA incremental_vacuum"));
  return Exec(writer_.get(), "PRAGMA wal_checkpoint(TRUNCATE)");
}

Status SqliteStore::ProbeWrite() {
  // A nearly full file system can take a probe (in WAL space a checkpoint
  // freed, or on its last blocks) and fail the next batch again: writes are
  // declared possible only with real room left.
  struct statvfs fs {};
  const std::string dir =
      path_.find('/') == std::string::npos ? "." : path_.substr(0, path_.rfind('/') + 1);
  if (statvfs(dir.c_str(), &fs) == 0) {
    const uint64_t free_bytes = static_cast<uint64_t>(fs.f_bavail) * fs.f_frsize;
    if (free_bytes < kProbeFreeBytes) {
      return Status::ResourceExhausted("the file system of the database has " +
                                       std::to_string(free_bytes >> 10) + " KiB free (disk full; " +
                                       std::to_string(kProbeFreeBytes >> 20) +
                                       " MiB needed to resume)");
    }
  }
  sqlite3* w = writer_.get();
  MAPD_RETURN_IF_ERROR(Exec(w, "BEGIN IMMEDIATE"));
  Status s = Exec(w, "INSERT INTO write_probe (data) VALUES (zeroblob(1048576))");
  if (s.ok()) s = Exec(w, "COMMIT");
  if (!s.ok()) {
    (void)Exec(w, "ROLLBACK");
    return s;
  }
  return Exec(w, "DELETE FROM write_probe");
}

// ---------------------------------------------------------------------------
// WriteTransaction

SqliteWriteTransaction::~SqliteWriteTransaction() {
  if (open_) (void)store_->rollback_.Run();
}

StatusOr<int64_t> SqliteWriteTransaction::RobotId(const std::string& name, int64_t now_ns) {
  if (auto it = new_robots_.find(name); it != new_robots_.end()) return it->second;
  {
    std::lock_guard<std::mutex> lock(store_->cache_mu_);
    if (auto it = store_->robot_ids_.find(name); it != store_->robot_ids_.end()) return it->second;
  }
  store_->insert_robot_.Bind(1, name).Bind(2, now_ns);
  MAPD_RETURN_IF_ERROR(store_->insert_robot_.Run());
  const int64_t id = sqlite3_last_insert_rowid(store_->writer_.get());
  new_robots_[name] = id;
  return id;
}

StatusOr<SessionFrame> SqliteWriteTransaction::Session(int64_t robot_id, const std::string& name,
                                                       FrameKind kind, int64_t now_ns) {
  const std::string key = SqliteStore::SessionKey(robot_id, name);
  if (auto it = new_sessions_.find(key); it != new_sessions_.end()) return it->second;
  {
    std::lock_guard<std::mutex> lock(store_->cache_mu_);
    if (auto it = store_->sessions_.find(key); it != store_->sessions_.end()) return it->second;
  }
  SessionFrame f;
  f.robot_id = robot_id;
  f.name = name;
  f.kind = kind;
  f.tied = kind == FrameKind::kMap;  // a map-frame session is tied by identity
  Statement& s = store_->insert_session_;
  s.Bind(1, robot_id).Bind(2, name).Bind(3, now_ns).Bind(4, static_cast<int64_t>(kind));
  s.Bind(5, static_cast<int64_t>(f.tied ? 1 : 0));
  if (f.tied) BindPose(s, 6, f.T_map_frame);
  MAPD_RETURN_IF_ERROR(s.Run());
  f.session_id = sqlite3_last_insert_rowid(store_->writer_.get());
  new_sessions_[key] = f;
  return f;
}

StatusOr<InsertResult> SqliteWriteTransaction::InsertObservation(const NewObservation& obs) {
  StatusOr<int64_t> robot_id = RobotId(obs.robot, obs.received_ns);
  if (!robot_id.ok()) return robot_id.status();
  StatusOr<SessionFrame> frame = Session(*robot_id, obs.session, obs.frame_kind, obs.received_ns);
  if (!frame.ok()) return frame.status();
  if (frame->kind != obs.frame_kind) {
    return Status::InvalidArgument(
        "session_frame disagrees with session '" + obs.session + "' of robot '" + obs.robot +
        "', which was opened with " +
        (frame->kind == FrameKind::kMap ? "SESSION_FRAME_MAP" : "SESSION_FRAME_LOCAL") +
        "; start a new session_id to change it");
  }
  InsertResult result;
  result.frame = *frame;

  const geometry::SensorObservation& f = *obs.features;
  payload_.clear();
  EncodeFeatures(f, &payload_);
  Statement& s = store_->insert_obs_;
  s.Bind(1, frame->session_id).Bind(2, static_cast<int64_t>(obs.seq)).Bind(3, obs.stamp_ns);
  s.Bind(4, obs.received_ns);
  BindPose(s, 5, f.T_frame_sensor);
  s.Bind(12, static_cast<int64_t>(f.lines.size())).Bind(13, static_cast<int64_t>(f.planes.size()));
  s.BindBlob(14, payload_.data(), payload_.size());
  MAPD_RETURN_IF_ERROR(s.Run());
  sqlite3* w = store_->writer_.get();
  if (sqlite3_changes(w) == 1) {
    result.stored = true;
    result.observation_id = sqlite3_last_insert_rowid(w);
    RobotDelta& d = robot_deltas_[*robot_id];
    d.batches += 1;
    d.features += f.lines.size() + f.planes.size();
    d.last_seen_ns = std::max(d.last_seen_ns, obs.received_ns);
    return result;
  }
  // A duplicate: report the earlier row.
  Statement& q = store_->find_obs_;
  q.Bind(1, frame->session_id).Bind(2, static_cast<int64_t>(obs.seq));
  StatusOr<bool> row = q.Step();
  if (row.ok() && *row) result.observation_id = q.ColumnInt(0);
  q.Reset();
  if (!row.ok()) return row.status();
  return result;
}

Status SqliteWriteTransaction::UpsertFused(const FusedRow& r) {
  Statement& s = store_->upsert_fused_;
  s.Bind(1, static_cast<int64_t>(r.id)).Bind(2, static_cast<int64_t>(r.kind));
  s.Bind(3, r.segment.a.x())
      .Bind(4, r.segment.a.y())
      .Bind(5, r.segment.b.x())
      .Bind(6, r.segment.b.y());
  s.Bind(7, r.z_min_m).Bind(8, r.z_max_m);
  s.Bind(9, static_cast<int64_t>(r.support)).Bind(10, static_cast<int64_t>(r.member_count));
  s.Bind(11, r.robots).Bind(12, static_cast<int64_t>(0));
  return s.Run();
}

Status SqliteWriteTransaction::DeleteFused(uint64_t id) {
  store_->delete_fused_.Bind(1, static_cast<int64_t>(id));
  return store_->delete_fused_.Run();
}

std::vector<int64_t> SqliteWriteTransaction::tied_session_ids() const {
  std::vector<int64_t> ids;
  for (const auto& [session_id, T] : new_ties_) ids.push_back(session_id);
  std::sort(ids.begin(), ids.end());
  return ids;
}

Status SqliteWriteTransaction::Commit() {
  for (const auto& [robot_id, d] : robot_deltas_) {
    Statement& s = store_->update_robot_;
    s.Bind(1, robot_id).Bind(2, static_cast<int64_t>(d.batches));
    s.Bind(3, static_cast<int64_t>(d.features)).Bind(4, d.last_seen_ns);
    MAPD_RETURN_IF_ERROR(s.Run());
  }
  MAPD_RETURN_IF_ERROR(store_->commit_.Run());
  open_ = false;
  std::lock_guard<std::mutex> lock(store_->cache_mu_);
  for (const auto& [name, id] : new_robots_) {
    store_->robot_ids_[name] = id;
    store_->robot_names_[id] = name;
  }
  for (const auto& [key, frame] : new_sessions_) store_->sessions_[key] = frame;
  for (const auto& [session_id, T] : new_ties_) {
    for (auto& [key, frame] : store_->sessions_) {
      if (frame.session_id != session_id) continue;
      frame.tied = true;
      frame.T_map_frame = T;
      frame.tied_through_observation = tie_point_;
      frame.tie_seq = tie_seq_;
    }
  }
  store_->max_tie_seq_ = std::max(store_->max_tie_seq_, tie_seq_);
  return Status::Ok();
}

StatusOr<uint64_t> SqliteWriteTransaction::DropRawObservations(int64_t received_before_ns,
                                                               int limit) {
  sqlite3* w = store_->writer_.get();
  // Only what every kept snapshot already reflects (so either can be
  // replayed from), only of sessions whose tie those snapshots reflect, and
  // never the newest row (ids must keep growing: SQLite reuses max(id) + 1).
  StatusOr<Statement> q = Statement::Prepare(
      w,
      "DELETE FROM observations WHERE id IN ("
      " SELECT o.id FROM observations o JOIN sessions s ON s.id = o.session_id,"
      "  (SELECT min(through_observation) AS through, min(through_tie_seq) AS tie_seq,"
      "          count(*) AS n FROM fusion_snapshots) AS snap"
      " WHERE snap.n > 0 AND o.id <= snap.through AND s.tied = 1 AND s.tie_seq <= snap.tie_seq"
      "  AND o.received_ns < ?1 AND o.id < (SELECT max(id) FROM observations)"
      " ORDER BY o.id LIMIT ?2)");
  if (!q.ok()) return q.status();
  q->Bind(1, received_before_ns).Bind(2, static_cast<int64_t>(limit));
  MAPD_RETURN_IF_ERROR(q->Run());
  const uint64_t dropped = static_cast<uint64_t>(sqlite3_changes(w));
  if (dropped > 0) MAPD_RETURN_IF_ERROR(Exec(w, "PRAGMA incremental_vacuum"));
  return dropped;
}

Status SqliteWriteTransaction::InsertSnapshot(const FusionSnapshot& snapshot, int keep,
                                              SnapshotParts parts) {
  sqlite3* w = store_->writer_.get();
  StatusOr<Statement> q = Statement::Prepare(
      w,
      "INSERT INTO fusion_snapshots (created_ns, map_version, through_observation, "
      "through_tie_seq, params, state, plane_state, parts, parts_key, state_bytes) "
      "VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7, ?8, ?9, ?10)");
  if (!q.ok()) return q.status();
  q->Bind(1, snapshot.created_ns).Bind(2, static_cast<int64_t>(snapshot.map_version));
  q->Bind(3, snapshot.through_observation).Bind(4, snapshot.through_tie_seq);
  q->Bind(5, std::string_view(snapshot.params));
  if (parts.count > 0) {
    // The bytes are in the parts; an empty plane_state blob says there is one.
    q->BindBlob(6, "", 0);
    if (snapshot.has_plane_state) q->BindBlob(7, "", 0);
    q->Bind(8, static_cast<int64_t>(parts.count)).Bind(9, parts.key);
    q->Bind(10, static_cast<int64_t>(snapshot.state.size()));
  } else {
    q->BindBlob(6, snapshot.state.data(), snapshot.state.size());
    if (snapshot.has_plane_state)
      q->BindBlob(7, snapshot.plane_state.data(), snapshot.plane_state.size());
    q->Bind(8, int64_t{0});
  }
  MAPD_RETURN_IF_ERROR(q->Run());
  StatusOr<Statement> prune =
      Statement::Prepare(w,
                         "DELETE FROM fusion_snapshots WHERE id NOT IN "
                         "(SELECT id FROM fusion_snapshots ORDER BY id DESC LIMIT ?1)");
  if (!prune.ok()) return prune.status();
  prune->Bind(1, static_cast<int64_t>(keep));
  return prune->Run();
}

Status SqliteWriteTransaction::InsertSnapshotPart(int64_t key, int index, std::string_view bytes) {
  StatusOr<Statement> q = Statement::Prepare(
      store_->writer_.get(),
      "INSERT INTO fusion_snapshot_parts (parts_key, part, bytes) VALUES (?1, ?2, ?3)");
  if (!q.ok()) return q.status();
  q->Bind(1, key).Bind(2, static_cast<int64_t>(index)).BindBlob(3, bytes.data(), bytes.size());
  return q->Run();
}

StatusOr<int> SqliteWriteTransaction::DeleteUnusedSnapshotParts(int limit) {
  sqlite3* w = store_->writer_.get();
  StatusOr<Statement> q = Statement::Prepare(
      w,
      "DELETE FROM fusion_snapshot_parts WHERE id IN (SELECT id FROM fusion_snapshot_parts "
      "WHERE parts_key NOT IN (SELECT parts_key FROM fusion_snapshots WHERE parts_key IS NOT "
      "NULL) LIMIT ?1)");
  if (!q.ok()) return q.status();
  q->Bind(1, static_cast<int64_t>(limit));
  MAPD_RETURN_IF_ERROR(q->Run());
  return sqlite3_changes(w);
}

// ---------------------------------------------------------------------------
// Submaps and merges (rare, large writes: statements are prepared per call).

StatusOr<int64_t> SqliteWriteTransaction::InsertSubmap(const NewSubmap& submap) {
  const SubmapMeta& m = submap.meta;
  StatusOr<int64_t> robot_id = RobotId(m.robot, m.created_ns);
  if (!robot_id.ok()) return robot_id.status();
  int64_t session_id = 0;
  if (!submap.session.empty()) {
    const std::string key = SqliteStore::SessionKey(*robot_id, submap.session);
    if (auto it = new_sessions_.find(key); it != new_sessions_.end()) {
      session_id = it->second.session_id;
    } else {
      std::lock_guard<std::mutex> lock(store_->cache_mu_);
      if (auto c = store_->sessions_.find(key); c != store_->sessions_.end())
        session_id = c->second.session_id;
    }
    if (session_id == 0) {
      return Status::FailedPrecondition(
          "session '" + submap.session + "' of robot '" + m.robot +
          "' is unknown: stream at least one batch in it before uploading "
          "a submap built in its frame, or leave session_id empty");
    }
  }
  sqlite3* w = store_->writer_.get();
  StatusOr<Statement> exists =
      Statement::Prepare(w, "SELECT id FROM submaps WHERE robot_id = ?1 AND name = ?2");
  if (!exists.ok()) return exists.status();
  exists->Bind(1, *robot_id).Bind(2, m.name);
  StatusOr<bool> found = exists->Step();
  if (!found.ok()) return found.status();
  if (*found) {
    return Status::AlreadyExists("robot '" + m.robot + "' already has a submap named '" + m.name +
                                 "' (id " + std::to_string(exists->ColumnInt(0)) +
                                 "); choose another name or delete that one first");
  }
  StatusOr<Statement> q = Statement::Prepare(
      w,
      "INSERT INTO submaps (robot_id, session_id, name, format, resolution, occupied, free, "
      "min_x, min_y, min_z, max_x, max_y, max_z, created_ns, data) "
      "VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7, ?8, ?9, ?10, ?11, ?12, ?13, ?14, ?15)");
  if (!q.ok()) return q.status();
  q->Bind(1, *robot_id);
  if (session_id != 0) q->Bind(2, session_id);  // else NULL
  q->Bind(3, m.name).Bind(4, static_cast<int64_t>(m.format)).Bind(5, m.resolution_m);
  q->Bind(6, static_cast<int64_t>(m.occupied_voxels)).Bind(7, static_cast<int64_t>(m.free_voxels));
  for (int i = 0; i < 3; ++i) {
    q->Bind(8 + i, m.bounds_min[i]);
    q->Bind(11 + i, m.bounds_max[i]);
  }
  q->Bind(14, m.created_ns);
  q->BindBlob(15, submap.data.data(), submap.data.size());
  MAPD_RETURN_IF_ERROR(q->Run());
  return sqlite3_last_insert_rowid(w);
}

Status SqliteWriteTransaction::DeleteSubmap(int64_t id) {
  sqlite3* w = store_->writer_.get();
  StatusOr<Statement> pinned = Statement::Prepare(
      w,
      "SELECT m.id FROM merges m WHERE m.status = 'accepted' AND (m.merged_submap_id = ?1 OR "
      "EXISTS (SELECT 1 FROM merge_inputs i WHERE i.merge_id = m.id AND i.submap_id = ?1)) "
      "ORDER BY m.id LIMIT 1");
  if (!pinned.ok()) return pinned.status();
  pinned->Bind(1, id);
  StatusOr<bool> row = pinned->Step();
  if (!row.ok()) return row.status();
  if (*row) {
    return Status::FailedPrecondition(
        "submap " + std::to_string(id) + " belongs to accepted merge " +
        std::to_string(pinned->ColumnInt(0)) + " (as an input or its result) and is kept with it");
  }
  StatusOr<Statement> del = Statement::Prepare(w, "DELETE FROM submaps WHERE id = ?1");
  if (!del.ok()) return del.status();
  del->Bind(1, id);
  MAPD_RETURN_IF_ERROR(del->Run());
  if (sqlite3_changes(w) == 0) return Status::NotFound("no submap with id " + std::to_string(id));
  return Status::Ok();
}

StatusOr<MergeIds> SqliteWriteTransaction::RecordMerge(const NewMerge& merge) {
  const MergeRecord& r = merge.record;
  sqlite3* w = store_->writer_.get();
  StatusOr<Statement> q = Statement::Prepare(
      w,
      "INSERT INTO merges (created_ns, status, reason, merged_submap_id, "
      "requested_by, decided_by, decided_ns) VALUES (?1, ?2, ?3, NULL, ?4, ?5, ?6)");
  if (!q.ok()) return q.status();
  q->Bind(1, r.created_ns)
      .Bind(2, std::string_view(MergeStateName(r.state)))
      .Bind(3, r.reason)
      .Bind(4, r.requested_by)
      .Bind(5, r.decided_by)
      .Bind(6, r.decided_ns);
  MAPD_RETURN_IF_ERROR(q->Run());
  MergeIds ids;
  ids.merge_id = sqlite3_last_insert_rowid(w);

  StatusOr<Statement> in = Statement::Prepare(
      w,
      "INSERT INTO merge_inputs (merge_id, submap_id, qw, qx, qy, qz, tx, ty, tz, matched_corners, "
      "residual_m, overlap_score, matched_points, source, support_fraction, shared_free_ratio, "
      "restart_spread_voxels, second_residual_m) "
      "VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7, ?8, ?9, ?10, ?11, ?12, ?13, ?14, ?15, ?16, ?17, ?18)");
  if (!in.ok()) return in.status();
  for (const MergeInputRecord& i : r.inputs) {
    in->Bind(1, ids.merge_id).Bind(2, i.submap_id);
    const std::string matched = EncodeMatched(i.matched);
    if (i.aligned) {
      BindPose(*in, 3, i.T_reference_submap);
      in->Bind(10, static_cast<int64_t>(i.matched_corners))
          .Bind(11, i.residual_m)
          .Bind(12, i.overlap_score);
      if (!matched.empty()) in->BindBlob(13, matched.data(), matched.size());
      // A figure that is not a number is stored as not measured.
      const auto figure = [](double v) { return std::isfinite(v) ? v : -1.0; };
      in->Bind(14, i.source)
          .Bind(15, figure(i.support_fraction))
          .Bind(16, figure(i.shared_free_ratio))
          .Bind(17, figure(i.restart_spread_voxels))
          .Bind(18, figure(i.second_residual_m));
    }
    MAPD_RETURN_IF_ERROR(in->Run());
  }
  if (r.state != MergeState::kAccepted && r.state != MergeState::kProposed) return ids;

  NewSubmap merged = merge.merged;
  merged.meta.robot = kMergedRobot;
  merged.meta.name = "merge-" + std::to_string(ids.merge_id);
  merged.session.clear();
  StatusOr<int64_t> submap_id = InsertSubmap(merged);
  if (!submap_id.ok()) return submap_id.status();
  ids.merged_submap_id = *submap_id;
  StatusOr<Statement> link =
      Statement::Prepare(w, "UPDATE merges SET merged_submap_id = ?2 WHERE id = ?1");
  if (!link.ok()) return link.status();
  link->Bind(1, ids.merge_id).Bind(2, ids.merged_submap_id);
  MAPD_RETURN_IF_ERROR(link->Run());
  return ids;
}

Status SqliteWriteTransaction::DecideMerge(int64_t id, MergeState state, const std::string& who,
                                           int64_t now_ns, const std::string& reason) {
  if (state != MergeState::kAccepted && state != MergeState::kRejected) {
    return Status::InvalidArgument("a merge is decided as accepted or rejected only");
  }
  sqlite3* w = store_->writer_.get();
  StatusOr<Statement> current = Statement::Prepare(w, "SELECT status FROM merges WHERE id = ?1");
  if (!current.ok()) return current.status();
  current->Bind(1, id);
  StatusOr<bool> row = current->Step();
  if (!row.ok()) return row.status();
  if (!*row) return Status::NotFound("no merge with id " + std::to_string(id));
  const std::string status = current->ColumnText(0);
  if (status != MergeStateName(MergeState::kProposed)) {
    return Status::FailedPrecondition("merge " + std::to_string(id) + " is " + status +
                                      "; only a proposed merge can be approved or rejected");
  }
  StatusOr<Statement> q = Statement::Prepare(
      w,
      "UPDATE merges SET status = ?2, decided_by = ?3, decided_ns = ?4, reason = ?5 WHERE id = ?1");
  if (!q.ok()) return q.status();
  q->Bind(1, id)
      .Bind(2, std::string_view(MergeStateName(state)))
      .Bind(3, who)
      .Bind(4, now_ns)
      .Bind(5, reason);
  return q->Run();
}

Status SqliteWriteTransaction::TieSession(int64_t session_id, const geometry::Rigid3& T_map_frame) {
  if (new_ties_.count(session_id) != 0) {
    return Status::FailedPrecondition("session " + std::to_string(session_id) + " is tied already");
  }
  StatusOr<SessionFrame> current = store_->GetSession(session_id);
  if (!current.ok()) return current.status();
  if (current->tied) {
    return Status::FailedPrecondition("session " + std::to_string(session_id) + " is tied already");
  }
  StatusOr<Statement> q =
      Statement::Prepare(store_->writer_.get(),
                         "UPDATE sessions SET tied = 1, qw = ?2, qx = ?3, qy = ?4, qz = ?5, tx = "
                         "?6, ty = ?7, tz = ?8, "
                         "tied_through_observation = ?9, tie_seq = ?10 WHERE id = ?1");
  if (!q.ok()) return q.status();
  if (tie_seq_ == 0) {
    std::lock_guard<std::mutex> lock(store_->cache_mu_);
    tie_seq_ = store_->max_tie_seq_ + 1;  // one sequence number per tying transaction
  }
  q->Bind(1, session_id);
  BindPose(*q, 2, T_map_frame);
  q->Bind(9, tie_point_).Bind(10, tie_seq_);
  MAPD_RETURN_IF_ERROR(q->Run());
  new_ties_[session_id] = T_map_frame;
  return Status::Ok();
}

// ---------------------------------------------------------------------------
// Reads

namespace {

constexpr const char* kObservationColumns =
    "SELECT o.id, s.robot_id, o.session_id, o.seq, o.stamp_ns, o.qw, o.qx, o.qy, o.qz, o.tx, "
    "o.ty, o.tz, o.payload, o.received_ns FROM observations o JOIN sessions s ON s.id = "
    "o.session_id ";

// Calls fn for every row of a query on kObservationColumns.
Status ForEachObservationRow(Statement& q,
                             const std::function<Status(const StoredObservation&)>& fn) {
  StoredObservation obs;
  for (;;) {
    StatusOr<bool> row = q.Step();
    if (!row.ok()) return row.status();
    if (!*row) return Status::Ok();
    obs.id = q.ColumnInt(0);
    obs.robot_id = q.ColumnInt(1);
    obs.session_id = q.ColumnInt(2);
    obs.seq = static_cast<uint64_t>(q.ColumnInt(3));
    obs.stamp_ns = q.ColumnInt(4);
    obs.received_ns = q.ColumnInt(13);
    obs.features.T_frame_sensor = ColumnPose(q, 5);
    Status s = DecodeFeatures(q.ColumnBlob(12), &obs.features);
    if (!s.ok())
      return Status(s.code(), "observation " + std::to_string(obs.id) + ": " + s.message());
    MAPD_RETURN_IF_ERROR(fn(obs));
  }
}

}  // namespace

Status SqliteStore::ForEachObservation(const std::function<Status(const StoredObservation&)>& fn) {
  std::lock_guard<std::mutex> lock(reader_mu_);
  StatusOr<Statement> q =
      Statement::Prepare(reader_.get(), std::string(kObservationColumns) + "ORDER BY o.id");
  if (!q.ok()) return q.status();
  return ForEachObservationRow(*q, fn);
}

Status SqliteStore::ForEachObservationBetween(
    int64_t after_id, int64_t through_id,
    const std::function<Status(const StoredObservation&)>& fn) {
  return ForEachObservationWhere("", after_id, through_id, fn);
}

Status SqliteStore::ForEachObservationWhere(
    const std::string& condition, int64_t after_id, int64_t through_id,
    const std::function<Status(const StoredObservation&)>& fn) {
  // Pages of rows (keyset: the next page starts after the last id seen), each
  // read under the reader lock and handed to `fn` after it is released: a long
  // replay (recovery, a tie of a large session) fuses for seconds, and other
  // readers (GetStats, ...) must not wait for that. (Calling `fn` under the
  // lock held them for the whole replay: std::mutex is not fair, and the
  // replay took it again at once for its next page.)
  constexpr int64_t kPageRows = 1024;
  const std::string sql = std::string(kObservationColumns) + "WHERE " + condition +
                          (condition.empty() ? "" : " AND ") +
                          "o.id > ?1 AND o.id <= ?2 ORDER BY o.id LIMIT ?3";
  std::vector<StoredObservation> page;
  for (int64_t last = after_id;;) {
    page.clear();
    {
      std::lock_guard<std::mutex> lock(reader_mu_);
      StatusOr<Statement> q = Statement::Prepare(reader_.get(), sql);
      if (!q.ok()) return q.status();
      q->Bind(1, last).Bind(2, through_id).Bind(3, kPageRows);
      MAPD_RETURN_IF_ERROR(ForEachObservationRow(*q, [&](const StoredObservation& obs) {
        page.push_back(obs);
        return Status::Ok();
      }));
    }
    for (const StoredObservation& obs : page) {
      last = obs.id;
      MAPD_RETURN_IF_ERROR(fn(obs));
    }
    if (static_cast<int64_t>(page.size()) < kPageRows) return Status::Ok();
  }
}

StatusOr<int64_t> SqliteStore::NewestObservationId() {
  std::lock_guard<std::mutex> lock(reader_mu_);
  StatusOr<Statement> q =
      Statement::Prepare(reader_.get(), "SELECT coalesce(max(id), 0) FROM observations");
  if (!q.ok()) return q.status();
  StatusOr<bool> row = q->Step();
  if (!row.ok()) return row.status();
  return q->ColumnInt(0);
}

StatusOr<FusionSnapshot> SqliteStore::LatestSnapshot(int skip) {
  std::lock_guard<std::mutex> lock(reader_mu_);
  StatusOr<Statement> q = Statement::Prepare(
      reader_.get(),
      "SELECT id, created_ns, map_version, through_observation, through_tie_seq, params, state, "
      "plane_state, parts, parts_key, state_bytes FROM fusion_snapshots ORDER BY id DESC "
      "LIMIT 1 OFFSET ?1");
  if (!q.ok()) return q.status();
  q->Bind(1, static_cast<int64_t>(skip));
  StatusOr<bool> row = q->Step();
  if (!row.ok()) return row.status();
  if (!*row) return Status::NotFound("no fusion snapshot");
  FusionSnapshot snap;
  snap.id = q->ColumnInt(0);
  snap.created_ns = q->ColumnInt(1);
  snap.map_version = static_cast<uint64_t>(q->ColumnInt(2));
  snap.through_observation = q->ColumnInt(3);
  snap.through_tie_seq = q->ColumnInt(4);
  snap.params = q->ColumnText(5);
  snap.state = std::string(q->ColumnBlob(6));
  snap.has_plane_state = !q->ColumnIsNull(7);
  if (snap.has_plane_state) snap.plane_state = std::string(q->ColumnBlob(7));
  const int64_t parts = q->ColumnInt(8);
  if (parts == 0) return snap;
  // In parts (InsertSnapshotPart): state, then plane_state.
  const int64_t key = q->ColumnInt(9);
  const int64_t state_bytes = q->ColumnInt(10);
  StatusOr<Statement> p = Statement::Prepare(
      reader_.get(),
      "SELECT part, bytes FROM fusion_snapshot_parts WHERE parts_key = ?1 ORDER BY part");
  if (!p.ok()) return p.status();
  p->Bind(1, key);
  std::string bytes;
  int64_t next = 0;
  for (;;) {
    StatusOr<bool> part = p->Step();
    if (!part.ok()) return part.status();
    if (!*part || p->ColumnInt(0) != next) break;
    bytes.append(p->ColumnBlob(1));
    ++next;
  }
  const auto have = static_cast<int64_t>(bytes.size());
  if (next != parts || have < state_bytes || (!snap.has_plane_state && have != state_bytes)) {
    return Status::Internal("fusion snapshot " + std::to_string(snap.id) + " has " +
                            std::to_string(next) + " of its " + std::to_string(parts) +
                            " parts in order (" + std::to_string(have) + " bytes)");
  }
  snap.state = bytes.substr(0, static_cast<size_t>(state_bytes));
  if (snap.has_plane_state) snap.plane_state = bytes.substr(static_cast<size_t>(state_bytes));
  return snap;
}

Status SqliteStore::ForEachObservationOfSessions(
    const std::vector<int64_t>& session_ids, int64_t max_id,
    const std::function<Status(const StoredObservation&)>& fn) {
  if (session_ids.empty()) return Status::Ok();
  std::string in;
  for (int64_t id : session_ids) in += (in.empty() ? "" : ",") + std::to_string(id);
  return ForEachObservationWhere("o.session_id IN (" + in + ")", 0, max_id, fn);
}

StatusOr<std::vector<SessionFrame>> SqliteStore::ListSessions() {
  std::lock_guard<std::mutex> lock(cache_mu_);
  std::vector<SessionFrame> out;
  out.reserve(sessions_.size());
  for (const auto& [key, f] : sessions_) out.push_back(f);
  return out;
}

StatusOr<SessionFrame> SqliteStore::GetSession(int64_t session_id) const {
  std::lock_guard<std::mutex> lock(cache_mu_);
  for (const auto& [key, f] : sessions_) {
    if (f.session_id == session_id) return f;
  }
  return Status::NotFound("no session with id " + std::to_string(session_id));
}

StatusOr<SessionFrame> SqliteStore::FindSession(const std::string& robot,
                                                const std::string& session) const {
  std::lock_guard<std::mutex> lock(cache_mu_);
  auto r = robot_ids_.find(robot);
  if (r != robot_ids_.end()) {
    auto it = sessions_.find(SessionKey(r->second, session));
    if (it != sessions_.end()) return it->second;
  }
  return Status::NotFound("robot '" + robot + "' has no session '" + session + "'");
}

namespace {

constexpr char kSubmapColumns[] =
    "SELECT s.id, r.name, s.name, coalesce(s.session_id, 0), s.format, s.resolution, s.occupied, "
    "s.free, s.min_x, s.min_y, s.min_z, s.max_x, s.max_y, s.max_z, s.created_ns, length(s.data) "
    "FROM submaps s JOIN robots r ON r.id = s.robot_id ";

SubmapMeta ColumnSubmap(const Statement& q) {
  SubmapMeta m;
  m.id = q.ColumnInt(0);
  m.robot = q.ColumnText(1);
  m.name = q.ColumnText(2);
  m.session_id = q.ColumnInt(3);
  m.format = static_cast<SubmapFormat>(q.ColumnInt(4));
  m.resolution_m = q.ColumnDouble(5);
  m.occupied_voxels = static_cast<uint64_t>(q.ColumnInt(6));
  m.free_voxels = static_cast<uint64_t>(q.ColumnInt(7));
  m.bounds_min = {q.ColumnDouble(8), q.ColumnDouble(9), q.ColumnDouble(10)};
  m.bounds_max = {q.ColumnDouble(11), q.ColumnDouble(12), q.ColumnDouble(13)};
  m.created_ns = q.ColumnInt(14);
  m.size_bytes = static_cast<uint64_t>(q.ColumnInt(15));
  return m;
}

}  // namespace

StatusOr<std::vector<SubmapMeta>> SqliteStore::ListSubmaps(const std::string& robot) {
  std::lock_guard<std::mutex> lock(reader_mu_);
  StatusOr<Statement> q = Statement::Prepare(
      reader_.get(), std::string(kSubmapColumns) + "WHERE ?1 = '' OR r.name = ?1 ORDER BY s.id");
  if (!q.ok()) return q.status();
  q->Bind(1, robot);
  std::vector<SubmapMeta> out;
  for (;;) {
    StatusOr<bool> row = q->Step();
    if (!row.ok()) return row.status();
    if (!*row) return out;
    out.push_back(ColumnSubmap(*q));
  }
}

StatusOr<SubmapMeta> SqliteStore::GetSubmap(int64_t id) {
  std::lock_guard<std::mutex> lock(reader_mu_);
  StatusOr<Statement> q =
      Statement::Prepare(reader_.get(), std::string(kSubmapColumns) + "WHERE s.id = ?1");
  if (!q.ok()) return q.status();
  q->Bind(1, id);
  StatusOr<bool> row = q->Step();
  if (!row.ok()) return row.status();
  if (!*row) return Status::NotFound("no submap with id " + std::to_string(id));
  return ColumnSubmap(*q);
}

StatusOr<std::string> SqliteStore::GetSubmapData(int64_t id) {
  std::lock_guard<std::mutex> lock(reader_mu_);
  StatusOr<Statement> q =
      Statement::Prepare(reader_.get(), "SELECT data FROM submaps WHERE id = ?1");
  if (!q.ok()) return q.status();
  q->Bind(1, id);
  StatusOr<bool> row = q->Step();
  if (!row.ok()) return row.status();
  if (!*row) return Status::NotFound("no submap with id " + std::to_string(id));
  return std::string(q->ColumnBlob(0));
}

StatusOr<std::vector<MergeRecord>> SqliteStore::ListMerges() {
  std::lock_guard<std::mutex> lock(reader_mu_);
  StatusOr<Statement> q =
      Statement::Prepare(reader_.get(),
                         "SELECT id, created_ns, status, reason, coalesce(merged_submap_id, 0), "
                         "requested_by, decided_by, decided_ns FROM merges ORDER BY id");
  if (!q.ok()) return q.status();
  std::vector<MergeRecord> out;
  for (;;) {
    StatusOr<bool> row = q->Step();
    if (!row.ok()) return row.status();
    if (!*row) break;
    MergeRecord r;
    r.id = q->ColumnInt(0);
    r.created_ns = q->ColumnInt(1);
    r.state = ParseMergeState(q->ColumnText(2));
    r.reason = q->ColumnText(3);
    r.merged_submap_id = q->ColumnInt(4);
    r.requested_by = q->ColumnText(5);
    r.decided_by = q->ColumnText(6);
    r.decided_ns = q->ColumnInt(7);
    out.push_back(std::move(r));
  }
  StatusOr<Statement> in = Statement::Prepare(
      reader_.get(),
      "SELECT merge_id, submap_id, qw, qx, qy, qz, tx, ty, tz, coalesce(matched_corners, 0), "
      "coalesce(residual_m, 0), coalesce(overlap_score, 0), qw IS NOT NULL, matched_points, "
      "coalesce(source, ''), coalesce(support_fraction, -1), coalesce(shared_free_ratio, -1), "
      "coalesce(restart_spread_voxels, -1), coalesce(second_residual_m, -1) "
      "FROM merge_inputs "
      "ORDER BY merge_id, rowid");
  if (!in.ok()) return in.status();
  std::unordered_map<int64_t, size_t> index;
  for (size_t i = 0; i < out.size(); ++i) index[out[i].id] = i;
  for (;;) {
    StatusOr<bool> row = in->Step();
    if (!row.ok()) return row.status();
    if (!*row) return out;
    auto it = index.find(in->ColumnInt(0));
    if (it == index.end()) continue;
    MergeInputRecord i;
    i.submap_id = in->ColumnInt(1);
    i.aligned = in->ColumnInt(12) != 0;
    if (i.aligned) i.T_reference_submap = ColumnPose(*in, 2);
    i.matched_corners = static_cast<int>(in->ColumnInt(9));
    i.residual_m = in->ColumnDouble(10);
    i.overlap_score = in->ColumnDouble(11);
    MAPD_RETURN_IF_ERROR(DecodeMatched(in->ColumnBlob(13), out[it->second].id, &i.matched));
    i.source = in->ColumnText(14);
    i.support_fraction = in->ColumnDouble(15);
    i.shared_free_ratio = in->ColumnDouble(16);
    i.restart_spread_voxels = in->ColumnDouble(17);
    i.second_residual_m = in->ColumnDouble(18);
    out[it->second].inputs.push_back(std::move(i));
  }
}

StatusOr<MergeRecord> SqliteStore::GetMerge(int64_t id) {
  StatusOr<std::vector<MergeRecord>> all = ListMerges();
  if (!all.ok()) return all.status();
  for (MergeRecord& r : *all) {
    if (r.id == id) return std::move(r);
  }
  return Status::NotFound("no merge with id " + std::to_string(id));
}

StatusOr<std::vector<FusedRow>> SqliteStore::LoadFused() {
  std::lock_guard<std::mutex> lock(reader_mu_);
  StatusOr<Statement> q = Statement::Prepare(
      reader_.get(),
      "SELECT id, kind, ax, ay, bx, by, z_min, z_max, support, member_count, robots "
      "FROM fused_features ORDER BY id");
  if (!q.ok()) return q.status();
  std::vector<FusedRow> out;
  for (;;) {
    StatusOr<bool> row = q->Step();
    if (!row.ok()) return row.status();
    if (!*row) return out;
    FusedRow r;
    r.id = static_cast<uint64_t>(q->ColumnInt(0));
    r.kind = static_cast<int>(q->ColumnInt(1));
    r.segment.a = {q->ColumnDouble(2), q->ColumnDouble(3)};
    r.segment.b = {q->ColumnDouble(4), q->ColumnDouble(5)};
    r.z_min_m = q->ColumnDouble(6);
    r.z_max_m = q->ColumnDouble(7);
    r.support = static_cast<uint32_t>(q->ColumnInt(8));
    r.member_count = static_cast<uint32_t>(q->ColumnInt(9));
    r.robots = q->ColumnText(10);
    out.push_back(std::move(r));
  }
}

StatusOr<std::vector<RobotSummary>> SqliteStore::ListRobots() {
  std::lock_guard<std::mutex> lock(reader_mu_);
  StatusOr<Statement> q = Statement::Prepare(
      reader_.get(),
      "SELECT r.id, r.name, r.first_seen_ns, r.last_seen_ns, r.batches, r.features, "
      "count(s.id), coalesce(min(s.tied), 0) FROM robots r LEFT JOIN sessions s ON s.robot_id = "
      "r.id "
      "WHERE r.name NOT GLOB '@*' GROUP BY r.id ORDER BY r.name");
  if (!q.ok()) return q.status();
  std::vector<RobotSummary> out;
  for (;;) {
    StatusOr<bool> row = q->Step();
    if (!row.ok()) return row.status();
    if (!*row) return out;
    RobotSummary r;
    r.id = q->ColumnInt(0);
    r.name = q->ColumnText(1);
    r.first_seen_ns = q->ColumnInt(2);
    r.last_seen_ns = q->ColumnInt(3);
    r.batches = static_cast<uint64_t>(q->ColumnInt(4));
    r.features = static_cast<uint64_t>(q->ColumnInt(5));
    r.sessions = static_cast<uint32_t>(q->ColumnInt(6));
    r.all_sessions_tied = q->ColumnInt(7) != 0;
    out.push_back(std::move(r));
  }
}

StatusOr<StoreCounts> SqliteStore::Counts() {
  std::lock_guard<std::mutex> lock(reader_mu_);
  StatusOr<Statement> q =
      Statement::Prepare(reader_.get(),
                         "SELECT (SELECT count(*) FROM robots WHERE name NOT GLOB '@*'), (SELECT "
                         "count(*) FROM sessions), "
                         "(SELECT coalesce(sum(batches), 0) FROM robots), (SELECT "
                         "coalesce(sum(features), 0) FROM robots), "
                         "(SELECT count(*) FROM fused_features), (SELECT count(*) FROM submaps)");
  if (!q.ok()) return q.status();
  StatusOr<bool> row = q->Step();
  if (!row.ok()) return row.status();
  StoreCounts c;
  c.robots = static_cast<uint64_t>(q->ColumnInt(0));
  c.sessions = static_cast<uint64_t>(q->ColumnInt(1));
  c.observations = static_cast<uint64_t>(q->ColumnInt(2));
  c.raw_features = static_cast<uint64_t>(q->ColumnInt(3));
  c.fused = static_cast<uint64_t>(q->ColumnInt(4));
  c.submaps = static_cast<uint64_t>(q->ColumnInt(5));
  return c;
}

std::string SqliteStore::RobotName(int64_t robot_id) const {
  std::lock_guard<std::mutex> lock(cache_mu_);
  auto it = robot_names_.find(robot_id);
  return it == robot_names_.end() ? std::string() : it->second;
}

uint64_t SqliteStore::SizeBytes() const { return FileSize(path_) + FileSize(path_ + "-wal"); }

}  // namespace mapd::storage
