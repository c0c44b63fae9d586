#include "storage/postgres/observation_log.h"

#include <algorithm>

#include "common/clock.h"
#include "storage/observation_codec.h"
#include "storage/postgres/pose_params.h"
#include "storage/postgres/schema.h"

namespace mapd::storage {
namespace {

constexpr const char* kObservationColumns =
    "SELECT o.id, s.robot_id, o.session_id, o.seq, o.stamp_ns, o.qw, o.qx, o.qy, o.qz, o.tx, "
    "o.ty, o.tz, o.payload, o.received_ns FROM observations o JOIN sessions s ON s.map = o.map "
    "AND s.id = o.session_id WHERE o.map = $1 AND o.id > $2 AND o.id <= $3 ";

}  // namespace

// ---------------------------------------------------------------------------
// PgWriteScope

PgWriteScope::PgWriteScope(PgConnection* conn) : conn_(conn), begun_(conn->Exec("BEGIN")) {
  open_ = begun_.ok();
}

PgWriteScope::~PgWriteScope() {
  if (open_) (void)conn_->Exec("ROLLBACK");
}

Status PgWriteScope::Commit() {
  if (!open_) return Status::FailedPrecondition("the transaction is not open");
  Status s = conn_->Exec("COMMIT");
  // A failed COMMIT ends the transaction too (PostgreSQL rolls it back).
  open_ = false;
  return s;
}

// ---------------------------------------------------------------------------
// PgObservationLog

StatusOr<std::unique_ptr<PgObservationLog>> PgObservationLog::Open(const std::string& conninfo,
                                                                   const std::string& map_id,
                                                                   const PgOwnership& ownership) {
  std::unique_ptr<PgObservationLog> log(new PgObservationLog());
  log->map_id_ = map_id;
  log->conninfo_ = conninfo;
  StatusOr<PgConnection> writer = PgConnection::Connect(conninfo);
  if (!writer.ok()) return writer.status();
  log->writer_ = std::move(writer).value();
  MAPD_RETURN_IF_ERROR(MigratePostgres(log->writer_));
  StatusOr<MapRow> row = EnsureMap(log->writer_, map_id, UnixNowNs());
  if (!row.ok()) return row.status();
  log->map_num_ = row->num;
  log->partition_ = row->partition;
  if (ownership.own) {
    const auto idle_ms = static_cast<int64_t>(ownership.idle_in_transaction_s * 1000);
    MAPD_RETURN_IF_ERROR(log->SetWriterSession("SET idle_in_transaction_session_timeout = " +
                                               std::to_string(std::max<int64_t>(idle_ms, 1))));
    StatusOr<MapLease> lease =
        AcquireMapLease(log->writer_, map_id, ownership.instance, ownership.lease_ttl_s);
    if (!lease.ok()) return lease.status();
    log->lease_ = *std::move(lease);
    log->owner_ = true;
  }
  StatusOr<PgConnection> reader = PgConnection::Connect(conninfo);
  if (!reader.ok()) return reader.status();
  log->reader_ = std::move(reader).value();
  MAPD_RETURN_IF_ERROR(log->LoadCaches());
  return log;
}

PgObservationLog::~PgObservationLog() {
  if (owner_ && writer_.healthy()) (void)ReleaseMapLease(writer_, lease_);
}

StatusOr<PgResult> PgObservationLog::ReadQuery(const std::string& sql, const PgParams& params) {
  if (!closed_.ok()) return closed_;
  return QueryReconnectingOnce(reader_, conninfo_, sql, params);  // a read changes nothing
}

Status PgObservationLog::SetWriterSession(const std::string& sql) {
  MAPD_RETURN_IF_ERROR(writer_.Exec(sql));
  writer_session_.push_back(sql);
  return Status::Ok();
}

Status PgObservationLog::Fence() {
  if (!owner_) return disowned_;
  Status s = FenceMapLease(writer_, lease_);
  if (s.code() == StatusCode::kFailedPrecondition) Disown(s);
  return s;
}

Status PgObservationLog::Release() {
  if (!owner_) return Status::Ok();
  Disown(Status::FailedPrecondition("map '" + map_id_ +
                                    "' was handed to another mapd; that one serves it now"));
  return ReleaseMapLease(writer_, lease_);
}

void PgObservationLog::Close(const Status& why) {
  if (owner_) (void)Release();
  std::lock_guard<std::mutex> lock(reader_mu_);
  closed_ = why;
  reader_ = PgConnection();
  writer_ = PgConnection();
}

Status PgObservationLog::CheckOpen() {
  std::lock_guard<std::mutex> lock(reader_mu_);
  return closed_;
}

void PgObservationLog::Disown(const Status& why) {
  disowned_ = why;
  owner_ = false;
}

Status PgObservationLog::Reconnect() {
  MAPD_RETURN_IF_ERROR(CheckOpen());
  // libpq does not always mark a connection broken on the first failure
  // after the server went away: ask it.
  if (writer_.healthy() && writer_.Exec("SELECT 1").ok()) return Status::Ok();
  StatusOr<PgConnection> again = PgConnection::Connect(conninfo_);
  if (!again.ok()) return again.status();
  writer_ = std::move(again).value();  // closes the broken one
  for (const std::string& sql : writer_session_) MAPD_RETURN_IF_ERROR(writer_.Exec(sql));
  if (!owner_) return Status::Ok();
  // Nobody else wrote while the epoch is this log's: every write of the map
  // is fenced by it.
  StatusOr<LeaseRow> now = GetMapLease(writer_, map_id_);
  if (!now.ok()) return now.status();
  if (now->owner != lease_.owner || now->epoch != lease_.epoch) {
    Disown(Status::FailedPrecondition(
        "map '" + map_id_ + "' was taken over by instance '" + now->owner + "' (" + now->address +
        ") while this mapd was disconnected from PostgreSQL; that instance serves it now"));
    return disowned_;
  }
  // But this log's own last commit may have landed although its answer was
  // lost with the connection (PostgreSQL crashed after committing): read the
  // caches again, or the next ids and new robots would collide with its rows.
  int64_t newest_before = 0, tie_before = 0;
  {
    std::lock_guard<std::mutex> lock(cache_mu_);
    newest_before = newest_observation_;
    tie_before = max_tie_seq_;
  }
  MAPD_RETURN_IF_ERROR(LoadCaches());
  std::lock_guard<std::mutex> lock(cache_mu_);
  if (newest_observation_ != newest_before || max_tie_seq_ != tie_before) {
    // Its observations (or a tie of frames) are stored but were never
    // fused, their robots told to resend (answered DUPLICATE): the engine is
    // out of step with the database. Give the map up; the ownership round
    // opens it again (the lease is still this instance's) and replays them.
    Disown(Status::FailedPrecondition(
        "map '" + map_id_ + "': a commit whose answer was lost with the connection did land (" +
        std::to_string(newest_observation_ - newest_before) +
        " observations); the map is opened again so that its fused map includes them"));
    return disowned_;
  }
  return Status::Ok();
}

Status PgObservationLog::LoadCaches() {
  PgParams map;
  map.Text(map_id_);
  StatusOr<PgResult> robots = writer_.Query("SELECT id, name FROM robots WHERE map = $1", map);
  if (!robots.ok()) return robots.status();
  StatusOr<PgResult> sessions = writer_.Query(
      "SELECT id, robot_id, name, frame_kind, tied, qw, qx, qy, qz, tx, ty, tz, "
      "tied_through_observation, tie_seq FROM sessions WHERE map = $1",
      map);
  if (!sessions.ok()) return sessions.status();
  StatusOr<PgResult> newest =
      writer_.Query("SELECT coalesce(max(id), 0) FROM observations WHERE map = $1", map);
  if (!newest.ok()) return newest.status();
  std::lock_guard<std::mutex> lock(cache_mu_);
  for (int i = 0; i < robots->rows(); ++i) {
    robot_ids_[robots->Text(i, 1)] = robots->Int(i, 0);
    robot_names_[robots->Int(i, 0)] = robots->Text(i, 1);
  }
  for (int i = 0; i < sessions->rows(); ++i) {
    SessionFrame f;
    f.session_id = sessions->Int(i, 0);
    f.robot_id = sessions->Int(i, 1);
    f.name = sessions->Text(i, 2);
    f.kind = static_cast<FrameKind>(sessions->Int(i, 3));
    f.tied = sessions->Int(i, 4) != 0;
    if (f.tied) f.T_map_frame = PoseAt(*sessions, i, 5);
    f.tied_through_observation = sessions->Int(i, 12);
    f.tie_seq = sessions->Int(i, 13);
    max_tie_seq_ = std::max(max_tie_seq_, f.tie_seq);
    sessions_[SessionKey(f.robot_id, sessions->Text(i, 2))] = f;
  }
  newest_observation_ = newest->Int(0, 0);
  return Status::Ok();
}

std::unique_ptr<PgObservationWriter> PgObservationLog::NewWriter() {
  return std::unique_ptr<PgObservationWriter>(new PgObservationWriter(this));
}

Status PgObservationLog::ForEachWhere(const std::string& condition,
                                      const std::vector<int64_t>& session_ids, int64_t after_id,
                                      int64_t through_id, const ObservationFn& fn) {
  // Keyset pages, each read under the reader lock and handed to `fn` after it
  // is released (as in the SQLite backend: a replay fuses for seconds, and
  // other readers must not wait for it).
  constexpr int64_t kPageRows = 1024;
  const std::string sql = std::string(kObservationColumns) + condition + " ORDER BY o.id LIMIT $4";
  std::vector<StoredObservation> page;
  for (int64_t last = after_id;;) {
    page.clear();
    {
      std::lock_guard<std::mutex> lock(reader_mu_);
      PgParams p;
      p.Text(map_id_).Int(last).Int(through_id).Int(kPageRows);
      if (!condition.empty()) p.IntArray(session_ids);
      StatusOr<PgResult> r = ReadQuery(sql, p);
      if (!r.ok()) return r.status();
      for (int i = 0; i < r->rows(); ++i) {
        StoredObservation obs;
        obs.id = r->Int(i, 0);
        obs.robot_id = r->Int(i, 1);
        obs.session_id = r->Int(i, 2);
        obs.seq = static_cast<uint64_t>(r->Int(i, 3));
        obs.stamp_ns = r->Int(i, 4);
        obs.received_ns = r->Int(i, 13);
        obs.features.T_frame_sensor = PoseAt(*r, i, 5);
        Status s = DecodeFeatures(r->Bytes(i, 12), &obs.features);
        if (!s.ok())
          return Status(s.code(), "observation " + std::to_string(obs.id) + ": " + s.message());
        page.push_back(std::move(obs));
      }
    }
    for (const StoredObservation& obs : page) {
      last = obs.id;
      MAPD_RETURN_IF_ERROR(fn(obs));
    }
    if (static_cast<int64_t>(page.size()) < kPageRows) return Status::Ok();
  }
}

Status PgObservationLog::ForEachObservation(const ObservationFn& fn) {
  return ForEachWhere("", {}, 0, INT64_MAX, fn);
}

Status PgObservationLog::ForEachObservationBetween(int64_t after_id, int64_t through_id,
                                                   const ObservationFn& fn) {
  return ForEachWhere("", {}, after_id, through_id, fn);
}

Status PgObservationLog::ForEachObservationOfSessions(const std::vector<int64_t>& session_ids,
                                                      int64_t max_id, const ObservationFn& fn) {
  return ForEachWhere("AND o.session_id = ANY($5)", session_ids, 0, max_id, fn);
}

StatusOr<int64_t> PgObservationLog::NewestObservationId() {
  std::lock_guard<std::mutex> lock(cache_mu_);
  return newest_observation_;
}

StatusOr<std::vector<SessionFrame>> PgObservationLog::ListSessions() {
  std::lock_guard<std::mutex> lock(cache_mu_);
  std::vector<SessionFrame> out;
  out.reserve(sessions_.size());
  for (const auto& [key, f] : sessions_) out.push_back(f);
  return out;
}

StatusOr<SessionFrame> PgObservationLog::GetSession(int64_t session_id) const {
  std::lock_guard<std::mutex> lock(cache_mu_);
  for (const auto& [key, f] : sessions_) {
    if (f.session_id == session_id) return f;
  }
  return Status::NotFound("no session " + std::to_string(session_id));
}

StatusOr<SessionFrame> PgObservationLog::FindSession(const std::string& robot,
                                                     const std::string& session) const {
  std::lock_guard<std::mutex> lock(cache_mu_);
  auto r = robot_ids_.find(robot);
  if (r != robot_ids_.end()) {
    auto it = sessions_.find(SessionKey(r->second, session));
    if (it != sessions_.end()) return it->second;
  }
  return Status::NotFound("robot '" + robot + "' has no session '" + session + "'");
}

StatusOr<std::vector<RobotSummary>> PgObservationLog::ListRobots() {
  std::lock_guard<std::mutex> lock(reader_mu_);
  PgParams p;
  p.Text(map_id_);
  StatusOr<PgResult> r = ReadQuery(
      "SELECT r.id, r.name, r.first_seen_ns, r.last_seen_ns, r.batches, r.features, "
      "count(s.id), coalesce(bool_and(s.tied), false) FROM robots r LEFT JOIN sessions s ON "
      "s.map = r.map AND s.robot_id = r.id WHERE r.map = $1 AND r.name NOT LIKE '@%' "
      "GROUP BY r.map, r.id ORDER BY r.name COLLATE \"C\"",
      p);
  if (!r.ok()) return r.status();
  std::vector<RobotSummary> out;
  for (int i = 0; i < r->rows(); ++i) {
    RobotSummary s;
    s.id = r->Int(i, 0);
    s.name = r->Text(i, 1);
    s.first_seen_ns = r->Int(i, 2);
    s.last_seen_ns = r->Int(i, 3);
    s.batches = static_cast<uint64_t>(r->Int(i, 4));
    s.features = static_cast<uint64_t>(r->Int(i, 5));
    s.sessions = static_cast<uint32_t>(r->Int(i, 6));
    s.all_sessions_tied = r->Int(i, 7) != 0;
    out.push_back(std::move(s));
  }
  return out;
}

std::string PgObservationLog::RobotName(int64_t robot_id) const {
  std::lock_guard<std::mutex> lock(cache_mu_);
  auto it = robot_names_.find(robot_id);
  return it == robot_names_.end() ? "" : it->second;
}

StatusOr<std::vector<StampedPose>> PgObservationLog::RecentPoses(int64_t session_id, int limit) {
  std::lock_guard<std::mutex> lock(reader_mu_);
  PgParams p;
  p.Text(map_id_).Int(session_id).Int(limit);
  // UNIQUE (map, session_id, seq) is an index: `limit` rows whatever the session's length.
  StatusOr<PgResult> r = ReadQuery(
      "SELECT seq, stamp_ns, qw, qx, qy, qz, tx, ty, tz FROM observations WHERE map = $1 AND "
      "session_id = $2 ORDER BY seq DESC LIMIT $3",
      p);
  if (!r.ok()) return r.status();
  std::vector<StampedPose> out;
  for (int i = 0; i < r->rows(); ++i) {
    StampedPose s;
    s.seq = static_cast<uint64_t>(r->Int(i, 0));
    s.stamp_ns = r->Int(i, 1);
    s.T_frame_sensor = PoseAt(*r, i, 2);
    out.push_back(s);
  }
  return out;
}

StatusOr<std::vector<SessionTrailRows>> PgObservationLog::ListTrails(const std::string& robot,
                                                                     uint32_t max_points) {
  const int64_t max_n = std::max<int64_t>(2, max_points);
  std::lock_guard<std::mutex> lock(reader_mu_);
  PgParams p;
  p.Text(map_id_).Text(robot).Int(max_n);
  // As the SQLite backend: a session longer than $3 keeps every k-th pose,
  // k = ceil(n / ($3 - 1)), and its last one: at most $3 poses.
  StatusOr<PgResult> r = ReadQuery(
      "SELECT r.name, s.name, s.id, o.seq, o.stamp_ns, o.tx, o.ty, o.tz, o.n FROM "
      "(SELECT session_id, seq, stamp_ns, tx, ty, tz, "
      "row_number() OVER (PARTITION BY session_id ORDER BY seq) AS rn, "
      "count(*) OVER (PARTITION BY session_id) AS n FROM observations WHERE map = $1) o "
      "JOIN sessions s ON s.map = $1 AND s.id = o.session_id "
      "JOIN robots r ON r.map = $1 AND r.id = s.robot_id "
      "WHERE r.name NOT LIKE '@%' AND ($2 = '' OR r.name = $2) AND "
      "(o.n <= $3 OR o.rn = o.n OR (o.rn - 1) % ((o.n + $3 - 2) / ($3 - 1)) = 0) "
      "ORDER BY r.name COLLATE \"C\", s.name COLLATE \"C\", o.seq",
      p);
  if (!r.ok()) return r.status();
  std::vector<SessionTrailRows> out;
  for (int i = 0; i < r->rows(); ++i) {
    const int64_t session_id = r->Int(i, 2);
    if (out.empty() || out.back().session_id != session_id) {
      SessionTrailRows t;
      t.robot = r->Text(i, 0);
      t.session = r->Text(i, 1);
      t.session_id = session_id;
      t.stored = static_cast<uint64_t>(r->Int(i, 8));
      out.push_back(std::move(t));
    }
    TrailPoint pt;
    pt.seq = static_cast<uint64_t>(r->Int(i, 3));
    pt.stamp_ns = r->Int(i, 4);
    pt.position = Eigen::Vector3d(r->Double(i, 5), r->Double(i, 6), r->Double(i, 7));
    out.back().points.push_back(pt);
  }
  return out;
}

// ---------------------------------------------------------------------------
// PgObservationWriter

PgObservationWriter::PgObservationWriter(PgObservationLog* log) : log_(log) {
  std::lock_guard<std::mutex> lock(log->cache_mu_);
  next_id_ = log->newest_observation_ + 1;
}

StatusOr<int64_t> PgObservationWriter::RobotId(const std::string& name, int64_t now_ns) {
  MAPD_RETURN_IF_ERROR(CheckOwner());
  if (auto it = new_robots_.find(name); it != new_robots_.end()) return it->second;
  {
    std::lock_guard<std::mutex> lock(log_->cache_mu_);
    if (auto it = log_->robot_ids_.find(name); it != log_->robot_ids_.end()) return it->second;
  }
  PgParams p;
  p.Text(log_->map_id_).Text(name).Int(now_ns);
  StatusOr<PgResult> r = log_->writer_.Query(
      "INSERT INTO robots (map, name, first_seen_ns, last_seen_ns) VALUES ($1, $2, $3, $3) "
      "RETURNING id",
      p);
  if (!r.ok()) return r.status();
  const int64_t id = r->Int(0, 0);
  new_robots_[name] = id;
  return id;
}

StatusOr<SessionFrame> PgObservationWriter::Session(int64_t robot_id, const std::string& name,
                                                    FrameKind kind, int64_t now_ns) {
  const std::string key = PgObservationLog::SessionKey(robot_id, name);
  if (auto it = new_sessions_.find(key); it != new_sessions_.end()) return it->second;
  {
    std::lock_guard<std::mutex> lock(log_->cache_mu_);
    if (auto it = log_->sessions_.find(key); it != log_->sessions_.end()) return it->second;
  }
  SessionFrame f;
  f.robot_id = robot_id;
  f.name = name;
  f.kind = kind;
  f.tied = kind == FrameKind::kMap;  // a map-frame session is tied by identity
  PgParams p;
  p.Text(log_->map_id_).Int(robot_id).Text(name).Int(now_ns).Int(static_cast<int64_t>(kind));
  p.Bool(f.tied);
  AddPose(p, f.T_map_frame);
  StatusOr<PgResult> r = log_->writer_.Query(
      "INSERT INTO sessions (map, robot_id, name, created_ns, frame_kind, tied, qw, qx, qy, qz, "
      "tx, ty, tz) VALUES ($1, $2, $3, $4, $5, $6, $7, $8, $9, $10, $11, $12, $13) RETURNING id",
      p);
  if (!r.ok()) return r.status();
  f.session_id = r->Int(0, 0);
  new_sessions_[key] = f;
  return f;
}

Status PgObservationWriter::CheckOwner() const {
  if (log_->owner_) return Status::Ok();
  if (!log_->disowned_.ok()) return log_->disowned_;
  return Status::FailedPrecondition("map '" + log_->map_id_ +
                                    "' was opened without its lease (for tokens and audit rows "
                                    "only); its data is written by the mapd that serves it");
}

StatusOr<SessionFrame> PgObservationWriter::FrameOf(const NewObservation& obs) {
  MAPD_RETURN_IF_ERROR(CheckOwner());
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
  return frame;
}

void PgObservationWriter::CountStored(const NewObservation& obs, int64_t robot_id) {
  RobotDelta& d = robot_deltas_[robot_id];
  d.batches += 1;
  d.features += obs.features->lines.size() + obs.features->planes.size();
  d.last_seen_ns = std::max(d.last_seen_ns, obs.received_ns);
}

StatusOr<std::vector<StatusOr<InsertResult>>> PgObservationWriter::InsertObservations(
    const std::vector<NewObservation>& batches) {
  std::vector<StatusOr<InsertResult>> results;
  results.reserve(batches.size());
  // Columns of the batches to insert, for unnest(): one statement for all.
  std::vector<size_t> index;  // into batches
  std::vector<int64_t> session, seq, stamp, received, lines, planes;
  std::vector<double> pose[7];
  std::vector<std::string> payloads;
  for (size_t i = 0; i < batches.size(); ++i) {
    const NewObservation& obs = batches[i];
    StatusOr<SessionFrame> frame = FrameOf(obs);
    if (!frame.ok() && frame.status().code() != StatusCode::kInvalidArgument) return frame.status();
    if (!frame.ok()) {
      results.push_back(frame.status());
      continue;
    }
    InsertResult r;
    r.frame = *frame;
    results.push_back(r);
    const geometry::SensorObservation& f = *obs.features;
    index.push_back(i);
    session.push_back(frame->session_id);
    seq.push_back(static_cast<int64_t>(obs.seq));
    stamp.push_back(obs.stamp_ns);
    received.push_back(obs.received_ns);
    const geometry::Rigid3& T = f.T_frame_sensor;
    const double values[7] = {T.rotation.w(),   T.rotation.x(),    T.rotation.y(),
                              T.rotation.z(),   T.translation.x(), T.translation.y(),
                              T.translation.z()};
    for (int k = 0; k < 7; ++k) pose[k].push_back(values[k]);
    lines.push_back(static_cast<int64_t>(f.lines.size()));
    planes.push_back(static_cast<int64_t>(f.planes.size()));
    payloads.emplace_back();
    EncodeFeatures(f, &payloads.back());
  }
  if (index.empty()) return results;
  PgParams p;
  p.Text(log_->map_id_).IntArray(session).IntArray(seq).IntArray(stamp).IntArray(received);
  for (const std::vector<double>& column : pose) p.DoubleArray(column);
  p.IntArray(lines).IntArray(planes);
  p.BytesArray({payloads.begin(), payloads.end()});
  p.Int(next_id_);
  // Ids in input order for the batches not stored before (the first of a
  // batch sent twice in this group): the same ids one by one would give.
  StatusOr<PgResult> r = log_->writer_.Query(
      "WITH input AS (SELECT * FROM unnest($2::int8[], $3::int8[], $4::int8[], $5::int8[], "
      "$6::float8[], $7::float8[], $8::float8[], $9::float8[], $10::float8[], $11::float8[], "
      "$12::float8[], $13::int8[], $14::int8[], $15::bytea[]) WITH ORDINALITY AS t(session_id, "
      "seq, stamp_ns, received_ns, qw, qx, qy, qz, tx, ty, tz, line_count, plane_count, payload, "
      "ord)), "
      "fresh AS (SELECT DISTINCT ON (session_id, seq) * FROM input i WHERE NOT EXISTS (SELECT 1 "
      "FROM observations o WHERE o.map = $1 AND o.session_id = i.session_id AND o.seq = i.seq) "
      "ORDER BY session_id, seq, ord), "
      "numbered AS (SELECT *, $16 + row_number() OVER (ORDER BY ord) - 1 AS id FROM fresh) "
      "INSERT INTO observations (map, id, session_id, seq, stamp_ns, received_ns, qw, qx, qy, qz, "
      "tx, ty, tz, line_count, plane_count, payload) SELECT $1, id, session_id, seq, stamp_ns, "
      "received_ns, qw, qx, qy, qz, tx, ty, tz, line_count, plane_count, payload FROM numbered "
      "RETURNING session_id, seq, id",
      p);
  if (!r.ok()) return r.status();
  struct Key {
    int64_t session, seq;
    bool operator==(const Key& o) const { return session == o.session && seq == o.seq; }
  };
  struct KeyHash {
    size_t operator()(const Key& k) const {
      return std::hash<int64_t>()(k.session) * 1000003u ^ std::hash<int64_t>()(k.seq);
    }
  };
  std::unordered_map<Key, std::pair<int64_t, bool>, KeyHash> stored;  // -> id, claimed
  for (int i = 0; i < r->rows(); ++i) stored[{r->Int(i, 0), r->Int(i, 1)}] = {r->Int(i, 2), false};
  next_id_ += r->rows();
  std::vector<size_t> earlier;  // positions in `index` of batches stored before this group
  for (size_t k = 0; k < index.size(); ++k) {
    InsertResult& result = *results[index[k]];
    auto it = stored.find({session[k], seq[k]});
    if (it == stored.end()) {
      earlier.push_back(k);
    } else {
      result.observation_id = it->second.first;
      result.stored = !it->second.second;  // a second copy in the group is a duplicate
      if (result.stored) CountStored(batches[index[k]], result.frame.robot_id);
      it->second.second = true;
    }
  }
  if (earlier.empty()) return results;
  std::vector<int64_t> dup_session, dup_seq;
  for (size_t k : earlier) {
    dup_session.push_back(session[k]);
    dup_seq.push_back(seq[k]);
  }
  PgParams q;
  q.Text(log_->map_id_).IntArray(dup_session).IntArray(dup_seq);
  StatusOr<PgResult> found = log_->writer_.Query(
      "SELECT o.session_id, o.seq, o.id FROM observations o JOIN unnest($2::int8[], $3::int8[]) "
      "AS d(session_id, seq) ON o.session_id = d.session_id AND o.seq = d.seq WHERE o.map = $1",
      q);
  if (!found.ok()) return found.status();
  std::unordered_map<Key, int64_t, KeyHash> ids;
  for (int i = 0; i < found->rows(); ++i)
    ids[{found->Int(i, 0), found->Int(i, 1)}] = found->Int(i, 2);
  for (size_t k : earlier) results[index[k]]->observation_id = ids[{session[k], seq[k]}];
  return results;
}

StatusOr<InsertResult> PgObservationWriter::InsertObservation(const NewObservation& obs) {
  // One batch is a group of one: the same statement, ids and answers.
  StatusOr<std::vector<StatusOr<InsertResult>>> results = InsertObservations({obs});
  if (!results.ok()) return results.status();
  return std::move(results->front());
}

Status PgObservationWriter::TieSession(int64_t session_id, const geometry::Rigid3& T_map_frame) {
  MAPD_RETURN_IF_ERROR(CheckOwner());
  const std::string tied = "session " + std::to_string(session_id) + " is tied already";
  if (new_ties_.count(session_id) != 0) return Status::FailedPrecondition(tied);
  StatusOr<SessionFrame> current = log_->GetSession(session_id);
  if (!current.ok()) {
    bool fresh = false;  // made in this transaction
    for (const auto& [key, f] : new_sessions_) fresh |= f.session_id == session_id;
    if (!fresh) return current.status();
  } else if (current->tied) {
    return Status::FailedPrecondition(tied);
  }
  if (tie_seq_ == 0) {
    std::lock_guard<std::mutex> lock(log_->cache_mu_);
    tie_seq_ = log_->max_tie_seq_ + 1;  // one sequence number per tying transaction
  }
  PgParams p;
  p.Text(log_->map_id_).Int(session_id);
  AddPose(p, T_map_frame);
  p.Int(tie_point_).Int(tie_seq_);
  StatusOr<PgResult> r = log_->writer_.Query(
      "UPDATE sessions SET tied = true, qw = $3, qx = $4, qy = $5, qz = $6, tx = $7, ty = $8, "
      "tz = $9, tied_through_observation = $10, tie_seq = $11 WHERE map = $1 AND id = $2",
      p);
  if (!r.ok()) return r.status();
  new_ties_[session_id] = T_map_frame;
  return Status::Ok();
}

int64_t PgObservationWriter::SessionId(int64_t robot_id, const std::string& name) const {
  const std::string key = PgObservationLog::SessionKey(robot_id, name);
  if (auto it = new_sessions_.find(key); it != new_sessions_.end()) return it->second.session_id;
  std::lock_guard<std::mutex> lock(log_->cache_mu_);
  auto it = log_->sessions_.find(key);
  return it == log_->sessions_.end() ? 0 : it->second.session_id;
}

std::vector<int64_t> PgObservationWriter::tied_session_ids() const {
  std::vector<int64_t> ids;
  for (const auto& [session_id, T] : new_ties_) ids.push_back(session_id);
  std::sort(ids.begin(), ids.end());
  return ids;
}

Status PgObservationWriter::BeforeCommit() {
  for (const auto& [robot_id, d] : robot_deltas_) {
    PgParams p;
    p.Text(log_->map_id_).Int(robot_id).Int(static_cast<int64_t>(d.batches));
    p.Int(static_cast<int64_t>(d.features)).Int(d.last_seen_ns);
    StatusOr<PgResult> r = log_->writer_.Query(
        "UPDATE robots SET batches = batches + $3, features = features + $4, "
        "last_seen_ns = greatest(last_seen_ns, $5) WHERE map = $1 AND id = $2",
        p);
    if (!r.ok()) return r.status();
  }
  return Status::Ok();
}

void PgObservationWriter::AfterCommit() {
  std::lock_guard<std::mutex> lock(log_->cache_mu_);
  for (const auto& [name, id] : new_robots_) {
    log_->robot_ids_[name] = id;
    log_->robot_names_[id] = name;
  }
  for (const auto& [key, frame] : new_sessions_) log_->sessions_[key] = frame;
  for (const auto& [session_id, T] : new_ties_) {
    for (auto& [key, frame] : log_->sessions_) {
      if (frame.session_id != session_id) continue;
      frame.tied = true;
      frame.T_map_frame = T;
      frame.tied_through_observation = tie_point_;
      frame.tie_seq = tie_seq_;
    }
  }
  log_->max_tie_seq_ = std::max(log_->max_tie_seq_, tie_seq_);
  log_->newest_observation_ = std::max(log_->newest_observation_, next_id_ - 1);
}

}  // namespace mapd::storage
