#include "storage/postgres/store.h"

#include "storage/postgres/schema.h"

namespace mapd::storage {

StatusOr<std::unique_ptr<PgStore>> PgStore::Open(const std::string& conninfo,
                                                 const std::string& map_id,
                                                 const StoreOptions& options,
                                                 const PgOwnership& ownership) {
  std::unique_ptr<PgStore> store(new PgStore());
  StatusOr<std::unique_ptr<PgObservationLog>> log =
      PgObservationLog::Open(conninfo, map_id, ownership);
  if (!log.ok()) return log.status();
  store->log_ = std::move(log).value();
  store->path_ = "postgresql map " + map_id;
  PgConnection& w = store->log_->writer();
  if (options.synchronous_full) {
    // "on" without a synchronous standby is a local commit: say so instead.
    StatusOr<PgResult> standbys = w.Query("SELECT current_setting('synchronous_standby_names')");
    if (!standbys.ok()) return standbys.status();
    if (standbys->Text(0, 0).empty()) {
      return Status::FailedPrecondition(
          "storage.sync = full on PostgreSQL needs a synchronous standby, and the server's "
          "synchronous_standby_names is empty (a commit would reach one disk only); configure "
          "one (docs/scale-out.md) or use storage.sync = normal");
    }
    MAPD_RETURN_IF_ERROR(store->log_->SetWriterSession("SET synchronous_commit = on"));
  } else {
    MAPD_RETURN_IF_ERROR(store->log_->SetWriterSession("SET synchronous_commit = local"));
  }
  return store;
}

StatusOr<std::unique_ptr<WriteTransaction>> PgStore::BeginWrite() {
  MAPD_RETURN_IF_ERROR(log_->CheckOpen());
  std::unique_ptr<PgWriteTransaction> txn(new PgWriteTransaction(this));
  MAPD_RETURN_IF_ERROR(txn->scope_.status());
  MAPD_RETURN_IF_ERROR(log_->Fence());
  return std::unique_ptr<WriteTransaction>(std::move(txn));
}

Status PgStore::ProbeWrite() {
  MAPD_RETURN_IF_ERROR(log_->Reconnect());
  PgConnection& w = log_->writer();
  PgWriteScope scope(&w);
  MAPD_RETURN_IF_ERROR(scope.status());
  MAPD_RETURN_IF_ERROR(log_->Fence());
  StatusOr<PgResult> r = w.Query(
      "INSERT INTO write_probe (map, data) VALUES ($1, decode(repeat('00', 1048576), 'hex'))",
      MapParams());
  if (!r.ok()) return r.status();
  r = w.Query("DELETE FROM write_probe WHERE map = $1", MapParams());
  if (!r.ok()) return r.status();
  return scope.Commit();
}

PgParams PgStore::MapParams() const {
  PgParams p;
  p.Text(log_->map_id());
  return p;
}

StatusOr<PgResult> PgStore::Read(const std::string& sql, PgParams params) const {
  std::lock_guard<std::mutex> lock(log_->reader_mu_);
  return log_->ReadQuery(sql, params);
}

StatusOr<std::string> PgStore::GetBlob(const std::string& owner, const std::string& what) const {
  PgParams p = MapParams();
  p.Text(owner);
  StatusOr<PgResult> r = Read(
      "SELECT bytes FROM blob_parts WHERE map = $1 AND owner = $2 ORDER BY part", std::move(p));
  if (!r.ok()) return r.status();
  if (r->rows() == 0) return Status::NotFound("no " + what);
  std::string out;
  for (int i = 0; i < r->rows(); ++i) out.append(r->Bytes(i, 0));
  return out;
}

StatusOr<StoreCounts> PgStore::Counts() {
  StatusOr<PgResult> r = Read(
      "SELECT (SELECT count(*) FROM robots WHERE map = $1 AND name NOT LIKE '@%'), "
      "(SELECT count(*) FROM sessions WHERE map = $1), "
      "(SELECT coalesce(sum(batches), 0)::int8 FROM robots WHERE map = $1), "
      "(SELECT coalesce(sum(features), 0)::int8 FROM robots WHERE map = $1), "
      "(SELECT count(*) FROM fused_features WHERE map = $1), "
      "(SELECT count(*) FROM submaps WHERE map = $1)",
      MapParams());
  if (!r.ok()) return r.status();
  StoreCounts c;
  c.robots = static_cast<uint64_t>(r->Int(0, 0));
  c.sessions = static_cast<uint64_t>(r->Int(0, 1));
  c.observations = static_cast<uint64_t>(r->Int(0, 2));
  c.raw_features = static_cast<uint64_t>(r->Int(0, 3));
  c.fused = static_cast<uint64_t>(r->Int(0, 4));
  c.submaps = static_cast<uint64_t>(r->Int(0, 5));
  return c;
}

uint64_t PgStore::SizeBytes() const {
  PgParams p;
  p.Text(log_->partition());
  StatusOr<PgResult> r = Read("SELECT pg_total_relation_size($1::text::regclass)", std::move(p));
  return r.ok() && r->rows() == 1 ? static_cast<uint64_t>(r->Int(0, 0)) : 0;
}

// ---------------------------------------------------------------------------
// PgWriteTransaction

PgWriteTransaction::PgWriteTransaction(PgStore* store)
    : store_(store), scope_(&store->log_->writer()), obs_(store->log_->NewWriter()) {}

PgParams PgWriteTransaction::MapParams() const { return store_->MapParams(); }

StatusOr<PgResult> PgWriteTransaction::Query(const std::string& sql, PgParams params) {
  return store_->log_->writer().Query(sql, params);
}

Status PgWriteTransaction::PutBlob(const std::string& owner, std::string_view bytes) {
  constexpr size_t kPartBytes = size_t{1} << 20;
  PgParams del = MapParams();
  del.Text(owner);
  StatusOr<PgResult> r =
      Query("DELETE FROM blob_parts WHERE map = $1 AND owner = $2", std::move(del));
  if (!r.ok()) return r.status();
  int part = 0;
  for (size_t at = 0; at < bytes.size() || part == 0; at += kPartBytes, ++part) {
    PgParams p = MapParams();
    p.Text(owner).Int(part).Bytes(bytes.substr(std::min(at, bytes.size()), kPartBytes));
    r = Query("INSERT INTO blob_parts (map, owner, part, bytes) VALUES ($1, $2, $3::int4, $4)",
              std::move(p));
    if (!r.ok()) return r.status();
    if (bytes.empty()) break;
  }
  return Status::Ok();
}

Status PgWriteTransaction::Commit() {
  MAPD_RETURN_IF_ERROR(obs_->BeforeCommit());
  MAPD_RETURN_IF_ERROR(scope_.Commit());
  obs_->AfterCommit();
  return Status::Ok();
}

}  // namespace mapd::storage
