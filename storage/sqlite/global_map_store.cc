// The global map's rows: submap placements and the built map
// (SqliteWriteTransaction::PlaceSubmap / PutGlobalMap, SqliteStore::GetGlobalMap /
// ListPlacements). The map itself is built by service/global_map_builder.h.
#include <cinttypes>
#include <cstdio>
#include <sstream>
#include <string>

#include "storage/blob_codec.h"
#include "storage/sqlite/pose_columns.h"
#include "storage/sqlite/sqlite.h"
#include "storage/sqlite/store.h"

namespace mapd::storage {
Status SqliteWriteTransaction::PlaceSubmap(int64_t submap_id, int64_t merge_id,
                                           const geometry::Rigid3& T_map_submap) {
  StatusOr<Statement> q = Statement::Prepare(
      store_->writer_.get(),
      "INSERT OR IGNORE INTO submap_placements (submap_id, merge_id, qw, qx, qy, qz, tx, ty, tz) "
      "VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7, ?8, ?9)");
  if (!q.ok()) return q.status();
  q->Bind(1, submap_id).Bind(2, merge_id);
  BindPose(*q, 3, T_map_submap);
  return q->Run();
}

Status SqliteWriteTransaction::PutGlobalMap(const GlobalMapRecord& map) {
  StatusOr<Statement> q = Statement::Prepare(
      store_->writer_.get(),
      "INSERT OR REPLACE INTO global_map (id, version, built_ns, resolution, occupied, free, "
      "members, data) VALUES (1, ?1, ?2, ?3, ?4, ?5, ?6, ?7)");
  if (!q.ok()) return q.status();
  const std::string members = EncodeMembers(map.members);
  q->Bind(1, static_cast<int64_t>(map.version))
      .Bind(2, map.built_ns)
      .Bind(3, map.resolution_m)
      .Bind(4, static_cast<int64_t>(map.occupied_voxels))
      .Bind(5, static_cast<int64_t>(map.free_voxels))
      .Bind(6, members)
      .BindBlob(7, map.data.data(), map.data.size());
  return q->Run();
}

Status SqliteWriteTransaction::DeleteGlobalMap() {
  StatusOr<Statement> q = Statement::Prepare(store_->writer_.get(), "DELETE FROM global_map");
  if (!q.ok()) return q.status();
  return q->Run();
}

StatusOr<GlobalMapRecord> SqliteStore::GetGlobalMap(bool with_data) {
  std::lock_guard<std::mutex> lock(reader_mu_);
  StatusOr<Statement> q = Statement::Prepare(
      reader_.get(), with_data
                         ? "SELECT version, built_ns, resolution, occupied, free, members, data "
                           "FROM global_map WHERE id = 1"
                         : "SELECT version, built_ns, resolution, occupied, free, members, x'' "
                           "FROM global_map WHERE id = 1");
  if (!q.ok()) return q.status();
  StatusOr<bool> row = q->Step();
  if (!row.ok()) return row.status();
  if (!*row) {
    return Status::NotFound(
        "no global map yet: no submap has a place in the map frame (accept a merge, or upload "
        "a submap in a session whose frame is tied)");
  }
  GlobalMapRecord map;
  map.version = static_cast<uint64_t>(q->ColumnInt(0));
  map.built_ns = q->ColumnInt(1);
  map.resolution_m = q->ColumnDouble(2);
  map.occupied_voxels = static_cast<uint64_t>(q->ColumnInt(3));
  map.free_voxels = static_cast<uint64_t>(q->ColumnInt(4));
  StatusOr<std::vector<GlobalMapMember>> members = DecodeMembers(q->ColumnText(5));
  if (!members.ok()) return members.status();
  map.members = *std::move(members);
  map.data = std::string(q->ColumnBlob(6));
  return map;
}

StatusOr<std::vector<SubmapPlacement>> SqliteStore::ListPlacements() {
  std::lock_guard<std::mutex> lock(reader_mu_);
  StatusOr<Statement> q = Statement::Prepare(
      reader_.get(),
      "SELECT submap_id, merge_id, qw, qx, qy, qz, tx, ty, tz FROM submap_placements "
      "ORDER BY submap_id");
  if (!q.ok()) return q.status();
  std::vector<SubmapPlacement> out;
  for (;;) {
    StatusOr<bool> row = q->Step();
    if (!row.ok()) return row.status();
    if (!*row) break;
    SubmapPlacement p;
    p.submap_id = q->ColumnInt(0);
    p.merge_id = q->ColumnInt(1);
    p.T_map_submap = ColumnPose(*q, 2);
    out.push_back(p);
  }
  return out;
}

}  // namespace mapd::storage
