// Tokens and the audit log on PostgreSQL (storage/auth_store.h). Tokens are
// the server's: one table for every map and every mapd of the database.
// Audit rows carry the map whose store wrote them.
#include "common/text_escape.h"
#include "storage/postgres/store.h"

namespace mapd::storage {
namespace {

constexpr char kTokenColumns[] =
    "SELECT id, name, role, robot_id, secret_sha256, created_ns, created_by, "
    "coalesce(revoked_ns, 0), maps FROM tokens ";

TokenRecord TokenAt(const PgResult& q, int i) {
  TokenRecord t;
  t.id = q.Int(i, 0);
  t.name = q.Text(i, 1);
  t.role = q.Text(i, 2);
  t.robot_id = q.Text(i, 3);
  t.secret_sha256 = q.Text(i, 4);
  t.created_ns = q.Int(i, 5);
  t.created_by = q.Text(i, 6);
  t.revoked_ns = q.Int(i, 7);
  t.maps = q.Text(i, 8);
  return t;
}

}  // namespace

StatusOr<int64_t> PgWriteTransaction::InsertToken(const TokenRecord& t) {
  PgParams p;
  p.Text(t.name).Text(t.role).Text(t.robot_id).Bytes(t.secret_sha256).Int(t.created_ns);
  p.Text(t.created_by).Text(t.maps);
  // ON CONFLICT instead of an error: a failed statement would abort the
  // whole group transaction.
  StatusOr<PgResult> r = Query(
      "INSERT INTO tokens (name, role, robot_id, secret_sha256, created_ns, created_by, maps) "
      "VALUES ($1, $2, $3, $4, $5, $6, $7) ON CONFLICT (name) DO NOTHING RETURNING id",
      std::move(p));
  if (!r.ok()) return r.status();
  if (r->rows() == 0)
    return Status::AlreadyExists("a token named '" + t.name +
                                 "' exists already (names are never reused)");
  return r->Int(0, 0);
}

Status PgWriteTransaction::RevokeToken(int64_t id, int64_t now_ns) {
  PgParams p;
  p.Int(id);
  StatusOr<PgResult> q =
      Query("SELECT coalesce(revoked_ns, 0) FROM tokens WHERE id = $1", std::move(p));
  if (!q.ok()) return q.status();
  if (q->rows() == 0) return Status::NotFound("no token with id " + std::to_string(id));
  if (q->Int(0, 0) != 0)
    return Status::FailedPrecondition("token " + std::to_string(id) + " is revoked already");
  PgParams u;
  u.Int(id).Int(now_ns);
  return Query("UPDATE tokens SET revoked_ns = $2 WHERE id = $1", std::move(u)).status();
}

Status PgWriteTransaction::AppendAudit(const AuditEntry& e) {
  // Each field is one line of visible text, whatever the caller passed.
  PgParams p = MapParams();
  p.Int(e.time_ns).Text(EscapeControlChars(e.who)).Text(EscapeControlChars(e.role));
  p.Text(EscapeControlChars(e.action)).Text(EscapeControlChars(e.target));
  p.Text(EscapeControlChars(e.result)).Text(EscapeControlChars(e.peer));
  p.Text(EscapeControlChars(e.credential));
  return Query(
             "INSERT INTO audit_log (map, time_ns, who, role, action, target, result, peer, "
             "credential) VALUES ($1, $2, $3, $4, $5, $6, $7, $8, $9)",
             std::move(p))
      .status();
}

StatusOr<int64_t> PgWriteTransaction::TrimDeniedAudit(int64_t keep) {
  PgParams p = MapParams();
  p.Int(keep);
  StatusOr<PgResult> r = Query(
      "DELETE FROM audit_log WHERE map = $1 AND id IN (SELECT id FROM audit_log WHERE map = $1 "
      "AND result LIKE 'denied%' ORDER BY id DESC OFFSET $2)",
      std::move(p));
  if (!r.ok()) return r.status();
  return r->affected();
}

StatusOr<TokenRecord> PgStore::GetToken(int64_t id) {
  PgParams p;
  p.Int(id);
  StatusOr<PgResult> q = Read(std::string(kTokenColumns) + "WHERE id = $1", std::move(p));
  if (!q.ok()) return q.status();
  if (q->rows() == 0) return Status::NotFound("no token with id " + std::to_string(id));
  return TokenAt(*q, 0);
}

StatusOr<std::vector<TokenRecord>> PgStore::ListTokens() {
  StatusOr<PgResult> q = Read(std::string(kTokenColumns) + "ORDER BY id", PgParams());
  if (!q.ok()) return q.status();
  std::vector<TokenRecord> out;
  for (int i = 0; i < q->rows(); ++i) out.push_back(TokenAt(*q, i));
  return out;
}

StatusOr<bool> PgStore::AnyTokenEver() {
  StatusOr<PgResult> q = Read("SELECT EXISTS (SELECT 1 FROM tokens)", PgParams());
  if (!q.ok()) return q.status();
  return q->Int(0, 0) != 0;
}

StatusOr<std::vector<AuditEntry>> PgStore::ListAudit(int limit) {
  PgParams p = MapParams();
  p.Int(limit);
  StatusOr<PgResult> q = Read(
      "SELECT id, time_ns, who, role, action, target, result, peer, credential FROM audit_log "
      "WHERE map = $1 ORDER BY id DESC LIMIT $2",
      std::move(p));
  if (!q.ok()) return q.status();
  std::vector<AuditEntry> out;
  for (int i = 0; i < q->rows(); ++i) {
    AuditEntry e;
    e.id = q->Int(i, 0);
    e.time_ns = q->Int(i, 1);
    e.who = q->Text(i, 2);
    e.role = q->Text(i, 3);
    e.action = q->Text(i, 4);
    e.target = q->Text(i, 5);
    e.result = q->Text(i, 6);
    e.peer = q->Text(i, 7);
    e.credential = q->Text(i, 8);
    out.push_back(std::move(e));
  }
  return out;
}

}  // namespace mapd::storage
