// Submaps, merges, placements and the global map on PostgreSQL
// (storage/submap_store.h). Submap files and the global map's bytes are in
// blob_parts (1 MiB parts), the rest in rows.
#include <cmath>
#include <unordered_map>

#include "storage/blob_codec.h"
#include "storage/postgres/pose_params.h"
#include "storage/postgres/store.h"

namespace mapd::storage {
namespace {

std::string SubmapOwner(int64_t id) { return "submap/" + std::to_string(id); }
constexpr char kGlobalMapOwner[] = "global_map";

constexpr char kSubmapColumns[] =
    "SELECT s.id, r.name, coalesce(s.session_id, 0), s.name, s.format, s.resolution, "
    "s.occupied, s.free, s.min_x, s.min_y, s.min_z, s.max_x, s.max_y, s.max_z, s.created_ns, "
    "s.size_bytes FROM submaps s JOIN robots r ON r.map = s.map AND r.id = s.robot_id "
    "WHERE s.map = $1 ";

SubmapMeta SubmapAt(const PgResult& q, int i) {
  SubmapMeta m;
  m.id = q.Int(i, 0);
  m.robot = q.Text(i, 1);
  m.session_id = q.Int(i, 2);
  m.name = q.Text(i, 3);
  m.format = static_cast<SubmapFormat>(q.Int(i, 4));
  m.resolution_m = q.Double(i, 5);
  m.occupied_voxels = static_cast<uint64_t>(q.Int(i, 6));
  m.free_voxels = static_cast<uint64_t>(q.Int(i, 7));
  m.bounds_min = {q.Double(i, 8), q.Double(i, 9), q.Double(i, 10)};
  m.bounds_max = {q.Double(i, 11), q.Double(i, 12), q.Double(i, 13)};
  m.created_ns = q.Int(i, 14);
  m.size_bytes = static_cast<uint64_t>(q.Int(i, 15));
  return m;
}

}  // namespace

StatusOr<int64_t> PgWriteTransaction::InsertSubmap(const NewSubmap& submap) {
  MAPD_RETURN_IF_ERROR(obs_->CheckOwner());
  const SubmapMeta& m = submap.meta;
  StatusOr<int64_t> robot_id = obs_->RobotId(m.robot, m.created_ns);
  if (!robot_id.ok()) return robot_id.status();
  int64_t session_id = 0;
  if (!submap.session.empty()) {
    session_id = obs_->SessionId(*robot_id, submap.session);
    if (session_id == 0) {
      return Status::FailedPrecondition(
          "session '" + submap.session + "' of robot '" + m.robot +
          "' is unknown: stream at least one batch in it before uploading "
          "a submap built in its frame, or leave session_id empty");
    }
  }
  PgParams e = MapParams();
  e.Int(*robot_id).Text(m.name);
  StatusOr<PgResult> exists =
      Query("SELECT id FROM submaps WHERE map = $1 AND robot_id = $2 AND name = $3", std::move(e));
  if (!exists.ok()) return exists.status();
  if (exists->rows() > 0) {
    return Status::AlreadyExists("robot '" + m.robot + "' already has a submap named '" + m.name +
                                 "' (id " + std::to_string(exists->Int(0, 0)) +
                                 "); choose another name or delete that one first");
  }
  PgParams p = MapParams();
  p.Int(*robot_id);
  if (session_id != 0) {
    p.Int(session_id);
  } else {
    p.Null();
  }
  p.Text(m.name).Int(static_cast<int64_t>(m.format)).Double(m.resolution_m);
  p.Int(static_cast<int64_t>(m.occupied_voxels)).Int(static_cast<int64_t>(m.free_voxels));
  for (int i = 0; i < 3; ++i) p.Double(m.bounds_min[i]);
  for (int i = 0; i < 3; ++i) p.Double(m.bounds_max[i]);
  p.Int(m.created_ns).Int(static_cast<int64_t>(submap.data.size()));
  StatusOr<PgResult> r = Query(
      "INSERT INTO submaps (map, robot_id, session_id, name, format, resolution, occupied, free, "
      "min_x, min_y, min_z, max_x, max_y, max_z, created_ns, size_bytes) VALUES ($1, $2, "
      "$3::int8, $4, $5::int4, $6, $7, $8, $9, $10, $11, $12, $13, $14, $15, $16) RETURNING id",
      std::move(p));
  if (!r.ok()) return r.status();
  const int64_t id = r->Int(0, 0);
  MAPD_RETURN_IF_ERROR(PutBlob(SubmapOwner(id), submap.data));
  return id;
}

Status PgWriteTransaction::DeleteSubmap(int64_t id) {
  MAPD_RETURN_IF_ERROR(obs_->CheckOwner());
  PgParams p = MapParams();
  p.Int(id);
  StatusOr<PgResult> pinned = Query(
      "SELECT m.id FROM merges m WHERE m.map = $1 AND m.status = 'accepted' AND "
      "(m.merged_submap_id = $2 OR EXISTS (SELECT 1 FROM merge_inputs i WHERE i.map = $1 AND "
      "i.merge_id = m.id AND i.submap_id = $2)) ORDER BY m.id LIMIT 1",
      std::move(p));
  if (!pinned.ok()) return pinned.status();
  if (pinned->rows() > 0) {
    return Status::FailedPrecondition(
        "submap " + std::to_string(id) + " belongs to accepted merge " +
        std::to_string(pinned->Int(0, 0)) + " (as an input or its result) and is kept with it");
  }
  PgParams d = MapParams();
  d.Int(id);
  StatusOr<PgResult> del = Query("DELETE FROM submaps WHERE map = $1 AND id = $2", std::move(d));
  if (!del.ok()) return del.status();
  if (del->affected() == 0) return Status::NotFound("no submap with id " + std::to_string(id));
  PgParams b = MapParams();
  b.Text(SubmapOwner(id));
  return Query("DELETE FROM blob_parts WHERE map = $1 AND owner = $2", std::move(b)).status();
}

StatusOr<MergeIds> PgWriteTransaction::RecordMerge(const NewMerge& merge) {
  MAPD_RETURN_IF_ERROR(obs_->CheckOwner());
  const MergeRecord& r = merge.record;
  PgParams p = MapParams();
  p.Int(r.created_ns).Text(MergeStateName(r.state)).Text(r.reason).Text(r.requested_by);
  p.Text(r.decided_by).Int(r.decided_ns);
  StatusOr<PgResult> row = Query(
      "INSERT INTO merges (map, created_ns, status, reason, merged_submap_id, requested_by, "
      "decided_by, decided_ns) VALUES ($1, $2, $3, $4, NULL, $5, $6, $7) RETURNING id",
      std::move(p));
  if (!row.ok()) return row.status();
  MergeIds ids;
  ids.merge_id = row->Int(0, 0);
  int position = 0;
  for (const MergeInputRecord& i : r.inputs) {
    const std::string matched = EncodeMatched(i.matched);
    PgParams in = MapParams();
    in.Int(ids.merge_id).Int(position++).Int(i.submap_id);
    if (i.aligned) {
      AddPose(in, i.T_reference_submap);
      in.Int(i.matched_corners).Double(i.residual_m).Double(i.overlap_score);
      if (matched.empty()) {
        in.Null();
      } else {
        in.Bytes(matched);
      }
      // A figure that is not a number is stored as not measured.
      const auto figure = [](double v) { return std::isfinite(v) ? v : -1.0; };
      in.Text(i.source).Double(figure(i.support_fraction)).Double(figure(i.shared_free_ratio));
      in.Double(figure(i.restart_spread_voxels)).Double(figure(i.second_residual_m));
    } else {
      for (int k = 0; k < 16; ++k) in.Null();  // pose, figures, pairs, source
    }
    StatusOr<PgResult> ins = Query(
        "INSERT INTO merge_inputs (map, merge_id, position, submap_id, qw, qx, qy, qz, tx, ty, "
        "tz, matched_corners, residual_m, overlap_score, matched_points, source, "
        "support_fraction, shared_free_ratio, restart_spread_voxels, second_residual_m) VALUES "
        "($1, $2, $3::int4, $4, $5::float8, $6::float8, $7::float8, $8::float8, $9::float8, "
        "$10::float8, $11::float8, $12::int4, $13::float8, $14::float8, $15::bytea, $16::text, "
        "$17::float8, $18::float8, $19::float8, $20::float8)",
        std::move(in));
    if (!ins.ok()) return ins.status();
  }
  if (r.state != MergeState::kAccepted && r.state != MergeState::kProposed) return ids;

  NewSubmap merged = merge.merged;
  merged.meta.robot = kMergedRobot;
  merged.meta.name = "merge-" + std::to_string(ids.merge_id);
  merged.session.clear();
  StatusOr<int64_t> submap_id = InsertSubmap(merged);
  if (!submap_id.ok()) return submap_id.status();
  ids.merged_submap_id = *submap_id;
  PgParams link = MapParams();
  link.Int(ids.merge_id).Int(ids.merged_submap_id);
  StatusOr<PgResult> l =
      Query("UPDATE merges SET merged_submap_id = $3 WHERE map = $1 AND id = $2", std::move(link));
  if (!l.ok()) return l.status();
  return ids;
}

Status PgWriteTransaction::DecideMerge(int64_t id, MergeState state, const std::string& who,
                                       int64_t now_ns, const std::string& reason) {
  MAPD_RETURN_IF_ERROR(obs_->CheckOwner());
  if (state != MergeState::kAccepted && state != MergeState::kRejected) {
    return Status::InvalidArgument("a merge is decided as accepted or rejected only");
  }
  PgParams c = MapParams();
  c.Int(id);
  StatusOr<PgResult> current =
      Query("SELECT status FROM merges WHERE map = $1 AND id = $2", std::move(c));
  if (!current.ok()) return current.status();
  if (current->rows() == 0) return Status::NotFound("no merge with id " + std::to_string(id));
  const std::string status = current->Text(0, 0);
  if (status != MergeStateName(MergeState::kProposed)) {
    return Status::FailedPrecondition("merge " + std::to_string(id) + " is " + status +
                                      "; only a proposed merge can be approved or rejected");
  }
  PgParams u = MapParams();
  u.Int(id).Text(MergeStateName(state)).Text(who).Int(now_ns).Text(reason);
  return Query(
             "UPDATE merges SET status = $3, decided_by = $4, decided_ns = $5, reason = $6 WHERE "
             "map = $1 AND id = $2",
             std::move(u))
      .status();
}

Status PgWriteTransaction::PlaceSubmap(int64_t submap_id, int64_t merge_id,
                                       const geometry::Rigid3& T_map_submap) {
  MAPD_RETURN_IF_ERROR(obs_->CheckOwner());
  PgParams p = MapParams();
  p.Int(submap_id).Int(merge_id);
  AddPose(p, T_map_submap);
  return Query(
             "INSERT INTO submap_placements (map, submap_id, merge_id, qw, qx, qy, qz, tx, ty, "
             "tz) VALUES ($1, $2, $3, $4, $5, $6, $7, $8, $9, $10) ON CONFLICT DO NOTHING",
             std::move(p))
      .status();
}

Status PgWriteTransaction::PutGlobalMap(const GlobalMapRecord& map) {
  MAPD_RETURN_IF_ERROR(obs_->CheckOwner());
  PgParams p = MapParams();
  p.Int(static_cast<int64_t>(map.version)).Int(map.built_ns).Double(map.resolution_m);
  p.Int(static_cast<int64_t>(map.occupied_voxels)).Int(static_cast<int64_t>(map.free_voxels));
  p.Text(EncodeMembers(map.members));
  StatusOr<PgResult> r = Query(
      "INSERT INTO global_map (map, version, built_ns, resolution, occupied, free, members) "
      "VALUES ($1, $2, $3, $4, $5, $6, $7) ON CONFLICT (map) DO UPDATE SET version = "
      "EXCLUDED.version, built_ns = EXCLUDED.built_ns, resolution = EXCLUDED.resolution, "
      "occupied = EXCLUDED.occupied, free = EXCLUDED.free, members = EXCLUDED.members",
      std::move(p));
  if (!r.ok()) return r.status();
  return PutBlob(kGlobalMapOwner, map.data);
}

Status PgWriteTransaction::DeleteGlobalMap() {
  MAPD_RETURN_IF_ERROR(obs_->CheckOwner());
  StatusOr<PgResult> r = Query("DELETE FROM global_map WHERE map = $1", MapParams());
  if (!r.ok()) return r.status();
  PgParams b = MapParams();
  b.Text(kGlobalMapOwner);
  return Query("DELETE FROM blob_parts WHERE map = $1 AND owner = $2", std::move(b)).status();
}

StatusOr<std::vector<SubmapMeta>> PgStore::ListSubmaps(const std::string& robot) {
  PgParams p = MapParams();
  p.Text(robot);
  StatusOr<PgResult> q = Read(
      std::string(kSubmapColumns) + "AND ($2 = '' OR r.name = $2) ORDER BY s.id", std::move(p));
  if (!q.ok()) return q.status();
  std::vector<SubmapMeta> out;
  for (int i = 0; i < q->rows(); ++i) out.push_back(SubmapAt(*q, i));
  return out;
}

StatusOr<SubmapMeta> PgStore::GetSubmap(int64_t id) {
  PgParams p = MapParams();
  p.Int(id);
  StatusOr<PgResult> q = Read(std::string(kSubmapColumns) + "AND s.id = $2", std::move(p));
  if (!q.ok()) return q.status();
  if (q->rows() == 0) return Status::NotFound("no submap with id " + std::to_string(id));
  return SubmapAt(*q, 0);
}

StatusOr<std::string> PgStore::GetSubmapData(int64_t id) {
  return GetBlob(SubmapOwner(id), "submap with id " + std::to_string(id));
}

StatusOr<std::vector<MergeRecord>> PgStore::ListMerges() {
  StatusOr<PgResult> q = Read(
      "SELECT id, created_ns, status, reason, coalesce(merged_submap_id, 0), requested_by, "
      "decided_by, decided_ns FROM merges WHERE map = $1 ORDER BY id",
      MapParams());
  if (!q.ok()) return q.status();
  std::vector<MergeRecord> out;
  std::unordered_map<int64_t, size_t> index;
  for (int i = 0; i < q->rows(); ++i) {
    MergeRecord r;
    r.id = q->Int(i, 0);
    r.created_ns = q->Int(i, 1);
    r.state = ParseMergeState(q->Bytes(i, 2));
    r.reason = q->Text(i, 3);
    r.merged_submap_id = q->Int(i, 4);
    r.requested_by = q->Text(i, 5);
    r.decided_by = q->Text(i, 6);
    r.decided_ns = q->Int(i, 7);
    index[r.id] = out.size();
    out.push_back(std::move(r));
  }
  StatusOr<PgResult> in = Read(
      "SELECT merge_id, submap_id, qw, qx, qy, qz, tx, ty, tz, coalesce(matched_corners, 0), "
      "coalesce(residual_m, 0), coalesce(overlap_score, 0), qw IS NOT NULL, "
      "coalesce(matched_points, ''::bytea), coalesce(source, ''), coalesce(support_fraction, -1), "
      "coalesce(shared_free_ratio, -1), coalesce(restart_spread_voxels, -1), "
      "coalesce(second_residual_m, -1) FROM merge_inputs WHERE map = $1 ORDER BY merge_id, "
      "position",
      MapParams());
  if (!in.ok()) return in.status();
  for (int k = 0; k < in->rows(); ++k) {
    auto it = index.find(in->Int(k, 0));
    if (it == index.end()) continue;
    MergeInputRecord i;
    i.submap_id = in->Int(k, 1);
    i.aligned = in->Int(k, 12) != 0;
    if (i.aligned) i.T_reference_submap = PoseAt(*in, k, 2);
    i.matched_corners = static_cast<int>(in->Int(k, 9));
    i.residual_m = in->Double(k, 10);
    i.overlap_score = in->Double(k, 11);
    MAPD_RETURN_IF_ERROR(DecodeMatched(in->Bytes(k, 13), out[it->second].id, &i.matched));
    i.source = in->Text(k, 14);
    i.support_fraction = in->Double(k, 15);
    i.shared_free_ratio = in->Double(k, 16);
    i.restart_spread_voxels = in->Double(k, 17);
    i.second_residual_m = in->Double(k, 18);
    out[it->second].inputs.push_back(std::move(i));
  }
  return out;
}

StatusOr<MergeRecord> PgStore::GetMerge(int64_t id) {
  StatusOr<std::vector<MergeRecord>> all = ListMerges();
  if (!all.ok()) return all.status();
  for (MergeRecord& r : *all) {
    if (r.id == id) return std::move(r);
  }
  return Status::NotFound("no merge with id " + std::to_string(id));
}

StatusOr<std::vector<SubmapPlacement>> PgStore::ListPlacements() {
  StatusOr<PgResult> q = Read(
      "SELECT submap_id, merge_id, qw, qx, qy, qz, tx, ty, tz FROM submap_placements WHERE map = "
      "$1 ORDER BY submap_id",
      MapParams());
  if (!q.ok()) return q.status();
  std::vector<SubmapPlacement> out;
  for (int i = 0; i < q->rows(); ++i) {
    SubmapPlacement p;
    p.submap_id = q->Int(i, 0);
    p.merge_id = q->Int(i, 1);
    p.T_map_submap = PoseAt(*q, i, 2);
    out.push_back(p);
  }
  return out;
}

StatusOr<GlobalMapRecord> PgStore::GetGlobalMap(bool with_data) {
  StatusOr<PgResult> q = Read(
      "SELECT version, built_ns, resolution, occupied, free, members FROM global_map WHERE map = "
      "$1",
      MapParams());
  if (!q.ok()) return q.status();
  if (q->rows() == 0) {
    return Status::NotFound(
        "no global map yet: no submap has a place in the map frame (accept a merge, or upload "
        "a submap in a session whose frame is tied)");
  }
  GlobalMapRecord map;
  map.version = static_cast<uint64_t>(q->Int(0, 0));
  map.built_ns = q->Int(0, 1);
  map.resolution_m = q->Double(0, 2);
  map.occupied_voxels = static_cast<uint64_t>(q->Int(0, 3));
  map.free_voxels = static_cast<uint64_t>(q->Int(0, 4));
  StatusOr<std::vector<GlobalMapMember>> members = DecodeMembers(q->Text(0, 5));
  if (!members.ok()) return members.status();
  map.members = *std::move(members);
  if (with_data) {
    StatusOr<std::string> data = GetBlob(kGlobalMapOwner, "global map bytes");
    if (!data.ok()) return data.status();
    map.data = *std::move(data);
  }
  return map;
}

}  // namespace mapd::storage
