// Fusion snapshots and raw retention on PostgreSQL (storage/snapshot_store.h).
#include "storage/postgres/store.h"

namespace mapd::storage {

Status PgWriteTransaction::InsertSnapshot(const FusionSnapshot& snapshot, int keep,
                                          SnapshotParts parts) {
  MAPD_RETURN_IF_ERROR(obs_->CheckOwner());
  PgParams p = MapParams();
  p.Int(snapshot.created_ns).Int(static_cast<int64_t>(snapshot.map_version));
  p.Int(snapshot.through_observation).Int(snapshot.through_tie_seq).Text(snapshot.params);
  if (parts.count > 0) {
    // The bytes are in the parts; an empty plane_state says there is one.
    p.Bytes("");
    if (snapshot.has_plane_state) {
      p.Bytes("");
    } else {
      p.Null();
    }
    p.Int(parts.count).Int(parts.key).Int(static_cast<int64_t>(snapshot.state.size()));
  } else {
    p.Bytes(snapshot.state);
    if (snapshot.has_plane_state) {
      p.Bytes(snapshot.plane_state);
    } else {
      p.Null();
    }
    p.Int(0).Null().Null();
  }
  StatusOr<PgResult> r = Query(
      "INSERT INTO fusion_snapshots (map, created_ns, map_version, through_observation, "
      "through_tie_seq, params, state, plane_state, parts, parts_key, state_bytes) VALUES ($1, "
      "$2, $3, $4, $5, $6, $7, $8::bytea, $9::int4, $10::int8, $11::int8)",
      std::move(p));
  if (!r.ok()) return r.status();
  PgParams prune = MapParams();
  prune.Int(keep);
  return Query(
             "DELETE FROM fusion_snapshots WHERE map = $1 AND id NOT IN (SELECT id FROM "
             "fusion_snapshots WHERE map = $1 ORDER BY id DESC LIMIT $2)",
             std::move(prune))
      .status();
}

Status PgWriteTransaction::InsertSnapshotPart(int64_t key, int index, std::string_view bytes) {
  MAPD_RETURN_IF_ERROR(obs_->CheckOwner());
  PgParams p = MapParams();
  p.Int(key).Int(index).Bytes(bytes);
  return Query(
             "INSERT INTO fusion_snapshot_parts (map, parts_key, part, bytes) VALUES ($1, $2, "
             "$3::int4, $4)",
             std::move(p))
      .status();
}

StatusOr<int> PgWriteTransaction::DeleteUnusedSnapshotParts(int limit) {
  MAPD_RETURN_IF_ERROR(obs_->CheckOwner());
  PgParams p = MapParams();
  p.Int(limit);
  StatusOr<PgResult> r = Query(
      "DELETE FROM fusion_snapshot_parts WHERE (map, parts_key, part) IN (SELECT map, "
      "parts_key, part FROM fusion_snapshot_parts WHERE map = $1 AND parts_key NOT IN (SELECT "
      "parts_key FROM fusion_snapshots WHERE map = $1 AND parts_key IS NOT NULL) LIMIT $2)",
      std::move(p));
  if (!r.ok()) return r.status();
  return static_cast<int>(r->affected());
}

StatusOr<uint64_t> PgWriteTransaction::DropRawObservations(int64_t received_before_ns, int limit) {
  MAPD_RETURN_IF_ERROR(obs_->CheckOwner());
  // As the SQLite backend: only what every kept snapshot reflects, only of
  // sessions whose tie they reflect, never the newest row (ids restart from
  // the newest stored + 1 when the map is opened again).
  PgParams p = MapParams();
  p.Int(received_before_ns).Int(limit);
  StatusOr<PgResult> r = Query(
      "DELETE FROM observations WHERE map = $1 AND id IN ("
      " SELECT o.id FROM observations o JOIN sessions s ON s.map = o.map AND s.id = o.session_id,"
      "  (SELECT min(through_observation) AS through, min(through_tie_seq) AS tie_seq,"
      "          count(*) AS n FROM fusion_snapshots WHERE map = $1) AS snap"
      " WHERE o.map = $1 AND snap.n > 0 AND o.id <= snap.through AND s.tied AND"
      "  s.tie_seq <= snap.tie_seq AND o.received_ns < $2 AND"
      "  o.id < (SELECT max(id) FROM observations WHERE map = $1)"
      " ORDER BY o.id LIMIT $3)",
      std::move(p));
  if (!r.ok()) return r.status();
  return static_cast<uint64_t>(r->affected());
}

StatusOr<FusionSnapshot> PgStore::LatestSnapshot(int skip) {
  PgParams p = MapParams();
  p.Int(skip);
  StatusOr<PgResult> q = Read(
      "SELECT id, created_ns, map_version, through_observation, through_tie_seq, params, state, "
      "plane_state, parts, coalesce(parts_key, 0), coalesce(state_bytes, 0) FROM "
      "fusion_snapshots WHERE map = $1 ORDER BY id DESC LIMIT 1 OFFSET $2",
      std::move(p));
  if (!q.ok()) return q.status();
  if (q->rows() == 0) return Status::NotFound("no fusion snapshot");
  FusionSnapshot snap;
  snap.id = q->Int(0, 0);
  snap.created_ns = q->Int(0, 1);
  snap.map_version = static_cast<uint64_t>(q->Int(0, 2));
  snap.through_observation = q->Int(0, 3);
  snap.through_tie_seq = q->Int(0, 4);
  snap.params = q->Text(0, 5);
  snap.state = q->Text(0, 6);
  snap.has_plane_state = !q->IsNull(0, 7);
  if (snap.has_plane_state) snap.plane_state = q->Text(0, 7);
  const int64_t parts = q->Int(0, 8);
  if (parts == 0) return snap;
  const int64_t key = q->Int(0, 9);
  const int64_t state_bytes = q->Int(0, 10);
  PgParams pp = MapParams();
  pp.Int(key);
  StatusOr<PgResult> rows = Read(
      "SELECT part, bytes FROM fusion_snapshot_parts WHERE map = $1 AND parts_key = $2 ORDER BY "
      "part",
      std::move(pp));
  if (!rows.ok()) return rows.status();
  std::string bytes;
  int64_t next = 0;
  for (int i = 0; i < rows->rows() && rows->Int(i, 0) == next; ++i, ++next)
    bytes.append(rows->Bytes(i, 1));
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

}  // namespace mapd::storage
