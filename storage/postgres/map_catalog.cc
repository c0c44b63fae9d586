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
  StatusOr<PgResult> r = Query("SELECT id FROM maps ORDER BY id COLLATE \"C\"", {});
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
  StatusOr<PgResult> r = Query("SELECT settings FROM maps WHERE id = $1", p);
  if (!r.ok()) return r.status();
  if (r->rows() == 0) return Status::NotFound("no map '" + id + "' in the PostgreSQL database");
  return r->Text(0, 0);
}

}  // namespace mapd::storage
