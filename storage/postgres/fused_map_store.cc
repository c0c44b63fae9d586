// The fused map's rows on PostgreSQL (storage/fused_map_store.h).
#include "storage/blob_codec.h"
#include "storage/postgres/store.h"

namespace mapd::storage {

// The one-row forms are the list forms with one row: one statement each way.
Status PgWriteTransaction::UpsertFused(const FusedRow& row) { return WriteFused({row}, {}); }

Status PgWriteTransaction::DeleteFused(uint64_t id) { return WriteFused({}, {id}); }

Status PgWriteTransaction::UpsertFusedPlane(const FusedPlaneRow& row) {
  return WriteFusedPlanes({row}, {});
}

Status PgWriteTransaction::DeleteFusedPlane(uint64_t id) { return WriteFusedPlanes({}, {id}); }

namespace {

std::vector<int64_t> Ids(const std::vector<uint64_t>& ids) {
  return std::vector<int64_t>(ids.begin(), ids.end());
}

}  // namespace

Status PgWriteTransaction::WriteFused(const std::vector<FusedRow>& upserts,
                                      const std::vector<uint64_t>& deletes) {
  MAPD_RETURN_IF_ERROR(obs_->CheckOwner());
  if (!upserts.empty()) {
    std::vector<int64_t> id, kind, support, members;
    std::vector<double> ax, ay, bx, by, z_min, z_max;
    std::vector<std::string_view> robots;
    for (const FusedRow& r : upserts) {
      id.push_back(static_cast<int64_t>(r.id));
      kind.push_back(r.kind);
      ax.push_back(r.segment.a.x());
      ay.push_back(r.segment.a.y());
      bx.push_back(r.segment.b.x());
      by.push_back(r.segment.b.y());
      z_min.push_back(r.z_min_m);
      z_max.push_back(r.z_max_m);
      support.push_back(r.support);
      members.push_back(r.member_count);
      robots.push_back(r.robots);
    }
    PgParams p = MapParams();
    p.IntArray(id).IntArray(kind).DoubleArray(ax).DoubleArray(ay).DoubleArray(bx);
    p.DoubleArray(by).DoubleArray(z_min).DoubleArray(z_max).IntArray(support).IntArray(members);
    p.TextArray(robots);
    StatusOr<PgResult> r = Query(
        "INSERT INTO fused_features (map, id, kind, ax, ay, bx, by, z_min, z_max, support, "
        "member_count, robots) SELECT $1, * FROM unnest($2::int8[], $3::int8[], $4::float8[], "
        "$5::float8[], $6::float8[], $7::float8[], $8::float8[], $9::float8[], $10::int8[], "
        "$11::int8[], $12::text[]) ON CONFLICT (map, id) DO UPDATE SET kind = EXCLUDED.kind, "
        "ax = EXCLUDED.ax, ay = EXCLUDED.ay, bx = EXCLUDED.bx, by = EXCLUDED.by, z_min = "
        "EXCLUDED.z_min, z_max = EXCLUDED.z_max, support = EXCLUDED.support, member_count = "
        "EXCLUDED.member_count, robots = EXCLUDED.robots",
        std::move(p));
    if (!r.ok()) return r.status();
  }
  if (deletes.empty()) return Status::Ok();
  PgParams d = MapParams();
  d.IntArray(Ids(deletes));
  return Query("DELETE FROM fused_features WHERE map = $1 AND id = ANY($2)", std::move(d)).status();
}

Status PgWriteTransaction::WriteFusedPlanes(const std::vector<FusedPlaneRow>& upserts,
                                            const std::vector<uint64_t>& deletes) {
  MAPD_RETURN_IF_ERROR(obs_->CheckOwner());
  if (!upserts.empty()) {
    std::vector<int64_t> id, support, members;
    std::vector<double> nx, ny, nz, offset, area, z_min, z_max;
    std::vector<std::string> boundaries;
    std::vector<std::string_view> robots;
    for (const FusedPlaneRow& r : upserts) {
      id.push_back(static_cast<int64_t>(r.id));
      nx.push_back(r.normal.x());
      ny.push_back(r.normal.y());
      nz.push_back(r.normal.z());
      offset.push_back(r.offset_m);
      boundaries.push_back(EncodeBoundary(r.boundary));
      area.push_back(r.area_m2);
      z_min.push_back(r.z_min_m);
      z_max.push_back(r.z_max_m);
      support.push_back(r.support);
      members.push_back(r.member_count);
      robots.push_back(r.robots);
    }
    PgParams p = MapParams();
    p.IntArray(id).DoubleArray(nx).DoubleArray(ny).DoubleArray(nz).DoubleArray(offset);
    p.BytesArray({boundaries.begin(), boundaries.end()}).DoubleArray(area).DoubleArray(z_min);
    p.DoubleArray(z_max).IntArray(support).IntArray(members).TextArray(robots);
    StatusOr<PgResult> r = Query(
        "INSERT INTO fused_planes (map, id, nx, ny, nz, \"offset\", boundary, area, z_min, z_max, "
        "support, member_count, robots) SELECT $1, * FROM unnest($2::int8[], $3::float8[], "
        "$4::float8[], $5::float8[], $6::float8[], $7::bytea[], $8::float8[], $9::float8[], "
        "$10::float8[], $11::int8[], $12::int8[], $13::text[]) ON CONFLICT (map, id) DO UPDATE "
        "SET nx = EXCLUDED.nx, ny = EXCLUDED.ny, nz = EXCLUDED.nz, \"offset\" = "
        "EXCLUDED.\"offset\", boundary = EXCLUDED.boundary, area = EXCLUDED.area, z_min = "
        "EXCLUDED.z_min, z_max = EXCLUDED.z_max, support = EXCLUDED.support, member_count = "
        "EXCLUDED.member_count, robots = EXCLUDED.robots",
        std::move(p));
    if (!r.ok()) return r.status();
  }
  if (deletes.empty()) return Status::Ok();
  PgParams d = MapParams();
  d.IntArray(Ids(deletes));
  return Query("DELETE FROM fused_planes WHERE map = $1 AND id = ANY($2)", std::move(d)).status();
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
