#include "storage/postgres/map_catalog.h"

#include "storage/postgres/schema.h"

namespace mapd::storage {

StatusOr<PgMapCatalog> PgMapCatalog::Open(const std::string& conninfo) {
  PgMapCatalog c;
  c.conninfo_ = conninfo;
  StatusOr<PgConnection> conn = PgConnection::Connect(conninfo);
  if (!conn.ok()) return conn.status();
  c.conn_ = std::move(conn).value();
  MAPD_RETURN_IF_ERROR(MigratePostgres(c.conn_));
  return c;
}

StatusOr<PgResult> PgMapCatalog::Query(const std::string& sql, const PgParams& params) {
  std::lock_guard<std::mutex> lock(*mu_);
  // Every statement here is one transaction.
  return QueryReconnectingOnce(conn_, conninfo_, sql, params);
}

StatusOr<std::vector<std::string>> PgMapCatalog::ListMaps() {
  StatusOr<PgResult> r = Query(
      "SELECT id FROM maps WHERE NOT importing AND archived_ns = 0 ORDER BY id COLLATE \"C\"", {});
  if (!r.ok()) return r.status();
  std::vector<std::string> ids;
  for (int i = 0; i < r->rows(); ++i) ids.push_back(r->Text(i, 0));
  return ids;
}

Status PgMapCatalog::CreateMap(const std::string& id, const std::string& settings, int64_t now_ns,
                               const PgInstance* owner, double ttl_s) {
  MAPD_RETURN_IF_ERROR(CheckPgMapId(id));
  PgParams p;
  p.Text(id).Int(now_ns).Text(settings);
  std::string sql =
      "INSERT INTO maps (id, created_ns, settings) VALUES ($1, $2, $3) ON CONFLICT (id) DO "
      "NOTHING";
  if (owner != nullptr) {
    p.Text(owner->name).Text(owner->address).Double(ttl_s);
    sql = "WITH made AS (" + sql +
          " RETURNING id) INSERT INTO map_leases (map, owner, address, epoch, expires_at) "
          "SELECT id, $4, $5, 0, clock_timestamp() + make_interval(secs => $6) FROM made";
  }
  StatusOr<PgResult> r = Query(sql, p);
  if (!r.ok()) return r.status();
  if (r->affected() == 0) return Status::AlreadyExists("map '" + id + "' exists already");
  return Status::Ok();
}

StatusOr<std::string> PgMapCatalog::Settings(const std::string& id) {
  PgParams p;
  p.Text(id);
  StatusOr<PgResult> r =
      Query("SELECT settings FROM maps WHERE id = $1 AND NOT importing AND archived_ns = 0", p);
  if (!r.ok()) return r.status();
  if (r->rows() == 0) return Status::NotFound("no map '" + id + "' in the PostgreSQL database");
  return r->Text(0, 0);
}

Status PgMapCatalog::BeginImport(const std::string& id, const std::string& settings, int64_t now_ns,
                                 const PgInstance& importer, double ttl_s, bool* restarted) {
  MAPD_RETURN_IF_ERROR(CheckPgMapId(id));
  *restarted = false;
  PgParams p;
  p.Text(id);
  StatusOr<PgResult> r = Query(
      "SELECT m.importing, l.owner, extract(epoch FROM l.expires_at - clock_timestamp())::float8 "
      "FROM maps m LEFT JOIN map_leases l ON l.map = m.id WHERE m.id = $1",
      p);
  if (!r.ok()) return r.status();
  if (r->rows() > 0) {
    if (r->Int(0, 0) == 0) {
      return Status::AlreadyExists("map '" + id +
                                   "' exists in the PostgreSQL database already; a migration "
                                   "makes a new map (choose another id)");
    }
    if (!r->IsNull(0, 1) && r->Double(0, 2) > 0 && r->Text(0, 1) != importer.name) {
      return Status::FailedPrecondition("map '" + id + "' is being imported by " + r->Text(0, 1) +
                                        " now; wait for it to end");
    }
    MAPD_RETURN_IF_ERROR(DiscardImport(id));
    *restarted = true;
  }
  PgParams q;
  q.Text(id).Int(now_ns).Text(settings).Text(importer.name).Text(importer.address).Double(ttl_s);
  r = Query(
      "WITH made AS (INSERT INTO maps (id, created_ns, settings, importing) VALUES ($1, $2, $3, "
      "true) ON CONFLICT (id) DO NOTHING RETURNING id) INSERT INTO map_leases (map, owner, "
      "address, epoch, expires_at) SELECT id, $4, $5, 0, clock_timestamp() + make_interval(secs "
      "=> $6) FROM made",
      q);
  if (!r.ok()) return r.status();
  if (r->affected() == 0)
    return Status::FailedPrecondition("map '" + id + "' was made meanwhile by someone else");
  return Status::Ok();
}

Status PgMapCatalog::FinishImport(const MapLease& lease) {
  PgParams p;
  p.Text(lease.map_id).Text(lease.owner).Int(lease.epoch);
  StatusOr<PgResult> r = Query(
      "UPDATE maps SET importing = false WHERE id = $1 AND importing AND EXISTS (SELECT 1 FROM "
      "map_leases WHERE map = $1 AND owner = $2 AND epoch = $3)",
      p);
  if (!r.ok()) return r.status();
  if (r->affected() == 0) {
    return Status::FailedPrecondition("map '" + lease.map_id +
                                      "' is no longer being imported under this lease (another "
                                      "import took it over)");
  }
  return Status::Ok();
}

Status PgMapCatalog::DiscardImport(const std::string& id) {
  PgParams p;
  p.Text(id);
  StatusOr<PgResult> r = Query("SELECT importing FROM maps WHERE id = $1", p);
  if (!r.ok()) return r.status();
  if (r->rows() == 0) return Status::Ok();
  if (r->Int(0, 0) == 0) {
    return Status::FailedPrecondition("map '" + id +
                                      "' is not being imported; only an import is discarded");
  }
  std::lock_guard<std::mutex> lock(*mu_);
  return DeleteMapRows(conn_, id);
}

Status PgMapCatalog::ArchiveMap(const MapLease& lease, int64_t now_ns) {
  PgParams p;
  p.Text(lease.map_id).Text(lease.owner).Int(lease.epoch).Int(now_ns);
  // One statement: the fence and the flag commit together.
  StatusOr<PgResult> r = Query(
      "WITH fenced AS (UPDATE map_leases SET owner = '', address = '', epoch = epoch + 1, "
      "expires_at = clock_timestamp() + interval '1000 years' WHERE map = $1 AND owner = $2 AND "
      "epoch = $3 RETURNING map) "
      "UPDATE maps SET archived_ns = $4 WHERE id IN (SELECT map FROM fenced) AND archived_ns = 0 "
      "AND NOT importing",
      p);
  if (!r.ok()) return r.status();
  if (r->affected() == 0) {
    return Status::FailedPrecondition("map '" + lease.map_id +
                                      "' is no longer served under this lease (another mapd took "
                                      "it over); nothing was archived");
  }
  return Status::Ok();
}

StatusOr<std::vector<PgMapCatalog::Archived>> PgMapCatalog::ListArchived() {
  StatusOr<PgResult> r = Query(
      "SELECT id, archived_ns FROM maps WHERE archived_ns <> 0 ORDER BY id COLLATE \"C\"", {});
  if (!r.ok()) return r.status();
  std::vector<Archived> out;
  for (int i = 0; i < r->rows(); ++i) out.push_back({r->Text(i, 0), r->Int(i, 1)});
  return out;
}

Status PgMapCatalog::RestoreMap(const std::string& id) {
  MAPD_RETURN_IF_ERROR(CheckPgMapId(id));
  PgParams p;
  p.Text(id);
  StatusOr<PgResult> r = Query(
      "WITH back AS (UPDATE maps SET archived_ns = 0 WHERE id = $1 AND archived_ns <> 0 "
      "RETURNING id) UPDATE map_leases SET expires_at = clock_timestamp() WHERE map IN (SELECT "
      "id FROM back)",
      p);
  if (!r.ok()) return r.status();
  if (r->affected() == 1) return Status::Ok();
  r = Query("SELECT archived_ns FROM maps WHERE id = $1", p);
  if (!r.ok()) return r.status();
  if (r->rows() == 0) return Status::NotFound("no map '" + id + "' in the PostgreSQL database");
  return Status::FailedPrecondition("map '" + id + "' is not archived");
}

Status PgMapCatalog::PurgeArchived(const std::string& id) {
  MAPD_RETURN_IF_ERROR(CheckPgMapId(id));
  std::lock_guard<std::mutex> lock(*mu_);
  return DeleteMapRows(conn_, id, /*only_archived=*/true);
}

}  // namespace mapd::storage
