// The fused map's rows on PostgreSQL (storage/fused_map_store.h).
#include "storage/blob_codec.h"
#include "storage/postgres/store.h"

namespace mapd::storage {

Status PgWriteTransaction::UpsertFused(const FusedRow& r) {
  MAPD_RETURN_IF_ERROR(obs_->CheckOwner());
  PgParams p = MapParams();
  p.Int(static_cast<int64_t>(r.id)).Int(r.kind);
  p.Double(r.segment.a.x()).Double(r.segment.a.y()).Double(r.segment.b.x()).Double(r.segment.b.y());
  p.Double(r.z_min_m).Double(r.z_max_m).Int(r.support).Int(r.member_count).Text(r.robots);
  return Query(
             "INSERT INTO fused_features (map, id, kind, ax, ay, bx, by, z_min, z_max, support, "
             "member_count, robots) VALUES ($1, $2, $3::int4, $4, $5, $6, $7, $8, $9, $10, $11, "
             "$12) ON CONFLICT (map, id) DO UPDATE SET kind = EXCLUDED.kind, ax = EXCLUDED.ax, "
             "ay = EXCLUDED.ay, bx = EXCLUDED.bx, by = EXCLUDED.by, z_min = EXCLUDED.z_min, "
             "z_max = EXCLUDED.z_max, support = EXCLUDED.support, member_count = "
             "EXCLUDED.member_count, robots = EXCLUDED.robots",
             std::move(p))
      .status();
}

Status PgWriteTransaction::DeleteFused(uint64_t id) {
  MAPD_RETURN_IF_ERROR(obs_->CheckOwner());
  PgParams p = MapParams();
  p.Int(static_cast<int64_t>(id));
  return Query("DELETE FROM fused_features WHERE map = $1 AND id = $2", std::move(p)).status();
}

Status PgWriteTransaction::UpsertFusedPlane(const FusedPlaneRow& r) {
  MAPD_RETURN_IF_ERROR(obs_->CheckOwner());
  const std::string boundary = EncodeBoundary(r.boundary);
  PgParams p = MapParams();
  p.Int(static_cast<int64_t>(r.id));
  p.Double(r.normal.x()).Double(r.normal.y()).Double(r.normal.z()).Double(r.offset_m);
  p.Bytes(boundary).Double(r.area_m2).Double(r.z_min_m).Double(r.z_max_m);
  p.Int(r.support).Int(r.member_count).Text(r.robots);
  return Query(
             "INSERT INTO fused_planes (map, id, nx, ny, nz, \"offset\", boundary, area, z_min, "
             "z_max, support, member_count, robots) VALUES ($1, $2, $3, $4, $5, $6, $7, $8, $9, "
             "$10, $11, $12, $13) ON CONFLICT (map, id) DO UPDATE SET nx = EXCLUDED.nx, ny = "
             "EXCLUDED.ny, nz = EXCLUDED.nz, \"offset\" = EXCLUDED.\"offset\", boundary = "
             "EXCLUDED.boundary, area = EXCLUDED.area, z_min = EXCLUDED.z_min, z_max = "
             "EXCLUDED.z_max, support = EXCLUDED.support, member_count = EXCLUDED.member_count, "
             "robots = EXCLUDED.robots",
             std::move(p))
      .status();
}

Status PgWriteTransaction::DeleteFusedPlane(uint64_t id) {
  MAPD_RETURN_IF_ERROR(obs_->CheckOwner());
  PgParams p = MapParams();
  p.Int(static_cast<int64_t>(id));
  return Query("DELETE FROM fused_planes WHERE map = $1 AND id = $2", std::move(p)).status();
}

StatusOr<std::vector<FusedRow>> PgStore::LoadFused() {
  StatusOr<PgResult> q = Read(
      "SELECT id, kind, ax, ay, bx, by, z_min, z_max, support, member_count, robots "
      "FROM fused_features WHERE map = $1 ORDER BY id",
      MapParams());
  if (!q.ok()) return q.status();
  std::vector<FusedRow> out;
  for (int i = 0; i < q->rows(); ++i) {
    FusedRow r;
    r.id = static_cast<uint64_t>(q->Int(i, 0));
    r.kind = static_cast<int>(q->Int(i, 1));
    r.segment.a = {q->Double(i, 2), q->Double(i, 3)};
    r.segment.b = {q->Double(i, 4), q->Double(i, 5)};
    r.z_min_m = q->Double(i, 6);
    r.z_max_m = q->Double(i, 7);
    r.support = static_cast<uint32_t>(q->Int(i, 8));
    r.member_count = static_cast<uint32_t>(q->Int(i, 9));
    r.robots = q->Text(i, 10);
    out.push_back(std::move(r));
  }
  return out;
}

StatusOr<std::vector<FusedPlaneRow>> PgStore::LoadFusedPlanes() {
  StatusOr<PgResult> q = Read(
      "SELECT id, nx, ny, nz, \"offset\", boundary, area, z_min, z_max, support, member_count, "
      "robots FROM fused_planes WHERE map = $1 ORDER BY id",
      MapParams());
  if (!q.ok()) return q.status();
  std::vector<FusedPlaneRow> out;
  for (int i = 0; i < q->rows(); ++i) {
    FusedPlaneRow r;
    r.id = static_cast<uint64_t>(q->Int(i, 0));
    r.normal = {q->Double(i, 1), q->Double(i, 2), q->Double(i, 3)};
    r.offset_m = q->Double(i, 4);
    MAPD_RETURN_IF_ERROR(DecodeBoundary(q->Bytes(i, 5), r.id, &r.boundary));
    r.area_m2 = q->Double(i, 6);
    r.z_min_m = q->Double(i, 7);
    r.z_max_m = q->Double(i, 8);
    r.support = static_cast<uint32_t>(q->Int(i, 9));
    r.member_count = static_cast<uint32_t>(q->Int(i, 10));
    r.robots = q->Text(i, 11);
    out.push_back(std::move(r));
  }
  return out;
}

}  // namespace mapd::storage
