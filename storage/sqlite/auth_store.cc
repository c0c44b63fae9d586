// Tokens and the audit log: the SQL side of server/service/auth.h.
// Writes run in the writer's transactions (one writer, as for everything
// else); reads on the reader connection.
#include "common/text_escape.h"
#include "storage/sqlite/store.h"

namespace mapd::storage {
namespace {

constexpr char kTokenColumns[] =
    "SELECT id, name, role, robot_id, secret_sha256, created_ns, created_by, "
    "coalesce(revoked_ns, 0), maps FROM tokens ";

TokenRecord ColumnToken(const Statement& q) {
  TokenRecord t;
  t.id = q.ColumnInt(0);
  t.name = q.ColumnText(1);
  t.role = q.ColumnText(2);
  t.robot_id = q.ColumnText(3);
  t.secret_sha256 = std::string(q.ColumnBlob(4));
  t.created_ns = q.ColumnInt(5);
  t.created_by = q.ColumnText(6);
  t.revoked_ns = q.ColumnInt(7);
  t.maps = q.ColumnText(8);
  return t;
}

}  // namespace

StatusOr<int64_t> SqliteWriteTransaction::InsertToken(const TokenRecord& t) {
  sqlite3* w = store_->writer_.get();
  StatusOr<Statement> exists = Statement::Prepare(w, "SELECT id FROM tokens WHERE name = ?1");
  if (!exists.ok()) return exists.status();
  exists->Bind(1, t.name);
  StatusOr<bool> found = exists->Step();
  if (!found.ok()) return found.status();
  if (*found)
    return Status::AlreadyExists("a token named '" + t.name +
                                 "' exists already (names are never reused)");
  StatusOr<Statement> q = Statement::Prepare(
      w,
      "INSERT INTO tokens (name, role, robot_id, secret_sha256, created_ns, created_by, maps) "
      "VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7)");
  if (!q.ok()) return q.status();
  q->Bind(1, t.name).Bind(2, t.role).Bind(3, t.robot_id);
  q->BindBlob(4, t.secret_sha256.data(), t.secret_sha256.size());
  q->Bind(5, t.created_ns).Bind(6, t.created_by).Bind(7, t.maps);
  MAPD_RETURN_IF_ERROR(q->Run());
  return static_cast<int64_t>(sqlite3_last_insert_rowid(w));
}

Status SqliteWriteTransaction::RevokeToken(int64_t id, int64_t now_ns) {
  sqlite3* w = store_->writer_.get();
  StatusOr<Statement> q =
      Statement::Prepare(w, "SELECT coalesce(revoked_ns, 0) FROM tokens WHERE id = ?1");
  if (!q.ok()) return q.status();
  q->Bind(1, id);
  StatusOr<bool> row = q->Step();
  if (!row.ok()) return row.status();
  if (!*row) return Status::NotFound("no token with id " + std::to_string(id));
  if (q->ColumnInt(0) != 0)
    return Status::FailedPrecondition("token " + std::to_string(id) + " is revoked already");
  StatusOr<Statement> u = Statement::Prepare(w, "UPDATE tokens SET revoked_ns = ?2 WHERE id = ?1");
  if (!u.ok()) return u.status();
  u->Bind(1, id).Bind(2, now_ns);
  return u->Run();
}

Status SqliteWriteTransaction::AppendAudit(const AuditEntry& e) {
  StatusOr<Statement> q = Statement::Prepare(store_->writer_.get(),
                                             "INSERT INTO audit_log (time_ns, who, role, action, "
                                             "target, result, peer, credential) "
                                             "VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7, ?8)");
  if (!q.ok()) return q.status();
  // Each field is one line of visible text, whatever the caller passed: an
  // audit row must not be able to forge another in a reader's terminal.
  q->Bind(1, e.time_ns)
      .Bind(2, EscapeControlChars(e.who))
      .Bind(3, EscapeControlChars(e.role))
      .Bind(4, EscapeControlChars(e.action))
      .Bind(5, EscapeControlChars(e.target))
      .Bind(6, EscapeControlChars(e.result))
      .Bind(7, EscapeControlChars(e.peer))
      .Bind(8, EscapeControlChars(e.credential));
  return q->Run();
}

StatusOr<int64_t> SqliteWriteTransaction::TrimDeniedAudit(int64_t keep) {
  sqlite3* w = store_->writer_.get();
  StatusOr<Statement> q = Statement::Prepare(
      w,
      "DELETE FROM audit_log WHERE id IN (SELECT id FROM audit_log WHERE result LIKE 'denied%' "
      "ORDER BY id DESC LIMIT -1 OFFSET ?1)");
  if (!q.ok()) return q.status();
  q->Bind(1, keep);
  MAPD_RETURN_IF_ERROR(q->Run());
  return static_cast<int64_t>(sqlite3_changes(w));
}

StatusOr<TokenRecord> SqliteStore::GetToken(int64_t id) {
  std::lock_guard<std::mutex> lock(reader_mu_);
  StatusOr<Statement> q =
      Statement::Prepare(reader_.get(), std::string(kTokenColumns) + "WHERE id = ?1");
  if (!q.ok()) return q.status();
  q->Bind(1, id);
  StatusOr<bool> row = q->Step();
  if (!row.ok()) return row.status();
  if (!*row) return Status::NotFound("no token with id " + std::to_string(id));
  return ColumnToken(*q);
}

StatusOr<std::vector<TokenRecord>> SqliteStore::ListTokens() {
  std::lock_guard<std::mutex> lock(reader_mu_);
  StatusOr<Statement> q =
      Statement::Prepare(reader_.get(), std::string(kTokenColumns) + "ORDER BY id");
  if (!q.ok()) return q.status();
  std::vector<TokenRecord> out;
  for (;;) {
    StatusOr<bool> row = q->Step();
    if (!row.ok()) return row.status();
    if (!*row) return out;
    out.push_back(ColumnToken(*q));
  }
}

StatusOr<bool> SqliteStore::AnyTokenEver() {
  std::lock_guard<std::mutex> lock(reader_mu_);
  StatusOr<Statement> q = Statement::Prepare(reader_.get(), "SELECT EXISTS (SELECT 1 FROM tokens)");
  if (!q.ok()) return q.status();
  StatusOr<bool> row = q->Step();
  if (!row.ok()) return row.status();
  return *row && q->ColumnInt(0) != 0;
}

StatusOr<std::vector<AuditEntry>> SqliteStore::ListAudit(int limit) {
  std::lock_guard<std::mutex> lock(reader_mu_);
  StatusOr<Statement> q = Statement::Prepare(reader_.get(),
                                             "SELECT id, time_ns, who, role, action, target, "
                                             "result, peer, credential FROM audit_log "
                                             "ORDER BY id DESC LIMIT ?1");
  if (!q.ok()) return q.status();
  q->Bind(1, static_cast<int64_t>(limit));
  std::vector<AuditEntry> out;
  for (;;) {
    StatusOr<bool> row = q->Step();
    if (!row.ok()) return row.status();
    if (!*row) return out;
    AuditEntry e;
    e.id = q->ColumnInt(0);
    e.time_ns = q->ColumnInt(1);
    e.who = q->ColumnText(2);
    e.role = q->ColumnText(3);
    e.action = q->ColumnText(4);
    e.target = q->ColumnText(5);
    e.result = q->ColumnText(6);
    e.peer = q->ColumnText(7);
    e.credential = q->ColumnText(8);
    out.push_back(std::move(e));
  }
}

}  // namespace mapd::storage
