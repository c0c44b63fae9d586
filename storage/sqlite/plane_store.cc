// Fused non-vertical planes: the SQL side of MapCore's plane fusion
// (fusion/plane_engine.h). Writes run in the writer's transactions; reads on
// the reader connection. Few rows change per commit, so statements are
// prepared per call.
#include <cstring>

#include "storage/blob_codec.h"
#include "storage/sqlite/store.h"

namespace mapd::storage {
Status SqliteWriteTransaction::UpsertFusedPlane(const FusedPlaneRow& r) {
  StatusOr<Statement> q = Statement::Prepare(
      store_->writer_.get(),
      "INSERT OR REPLACE INTO fused_planes (id, nx, ny, nz, offset, boundary, area, z_min, z_max, "
      "support, member_count, robots, updated_ns) "
      "VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7, ?8, ?9, ?10, ?11, ?12, ?13)");
  if (!q.ok()) return q.status();
  const std::string boundary = EncodeBoundary(r.boundary);
  q->Bind(1, static_cast<int64_t>(r.id));
  q->Bind(2, r.normal.x()).Bind(3, r.normal.y()).Bind(4, r.normal.z()).Bind(5, r.offset_m);
  q->BindBlob(6, boundary.data(), boundary.size());
  q->Bind(7, r.area_m2).Bind(8, r.z_min_m).Bind(9, r.z_max_m);
  q->Bind(10, static_cast<int64_t>(r.support)).Bind(11, static_cast<int64_t>(r.member_count));
  q->Bind(12, std::string_view(r.robots)).Bind(13, static_cast<int64_t>(0));
  return q->Run();
}

Status SqliteWriteTransaction::DeleteFusedPlane(uint64_t id) {
  StatusOr<Statement> q =
      Statement::Prepare(store_->writer_.get(), "DELETE FROM fused_planes WHERE id = ?1");
  if (!q.ok()) return q.status();
  q->Bind(1, static_cast<int64_t>(id));
  return q->Run();
}

StatusOr<std::vector<FusedPlaneRow>> SqliteStore::LoadFusedPlanes() {
  std::lock_guard<std::mutex> lock(reader_mu_);
  StatusOr<Statement> q = Statement::Prepare(
      reader_.get(),
      "SELECT id, nx, ny, nz, offset, boundary, area, z_min, z_max, support, member_count, robots "
      "FROM fused_planes ORDER BY id");
  if (!q.ok()) return q.status();
  std::vector<FusedPlaneRow> out;
  for (;;) {
    StatusOr<bool> row = q->Step();
    if (!row.ok()) return row.status();
    if (!*row) return out;
    FusedPlaneRow r;
    r.id = static_cast<uint64_t>(q->ColumnInt(0));
    r.normal = {q->ColumnDouble(1), q->ColumnDouble(2), q->ColumnDouble(3)};
    r.offset_m = q->ColumnDouble(4);
    MAPD_RETURN_IF_ERROR(DecodeBoundary(q->ColumnBlob(5), r.id, &r.boundary));
    r.area_m2 = q->ColumnDouble(6);
    r.z_min_m = q->ColumnDouble(7);
    r.z_max_m = q->ColumnDouble(8);
    r.support = static_cast<uint32_t>(q->ColumnInt(9));
    r.member_count = static_cast<uint32_t>(q->ColumnInt(10));
    r.robots = q->ColumnText(11);
    out.push_back(std::move(r));
  }
}

}  // namespace mapd::storage
