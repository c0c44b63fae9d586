#include "service/access_control.h"

#include "common/clock.h"
#include "service/log.h"
#include "service/map_id.h"
#include "service/token.h"

namespace mapd::service {
namespace {

constexpr char kBearer[] = "Bearer ";

bool IsWrite(Permission p) {
  return p == Permission::kWrite || p == Permission::kDelete || p == Permission::kMerge ||
         p == Permission::kManageTokens || p == Permission::kManageMaps;
}

std::string_view View(const grpc::string_ref& s) { return std::string_view(s.data(), s.size()); }

// Who a caller without a credential is in the open mode (gRPC and web alike).
Principal AnonymousOperator() {
  Principal p;
  p.name = "anonymous";
  p.role = Role::kOperator;
  p.anonymous = true;
  p.credential = "none";
  return p;
}

}  // namespace

StatusOr<bool> AccessControl::Required() {
  if (options_.required || options_.client_certs || tokens_exist_.load()) return true;
  StatusOr<bool> any = core_->store().AnyTokenEver();
  // A database that cannot be read fails closed, but as a refusal to retry
  // (UNAVAILABLE), not a verdict on the caller: robots give up on
  // UNAUTHENTICATED, and must not for a database restart.
  if (!any.ok()) {
    return Status::Unavailable(
        "cannot tell whether calls need a credential: " + any.status().message() + "; retry");
  }
  if (*any) tokens_exist_ = true;
  return *any;
}

StatusOr<Principal> AccessControl::FromToken(std::string_view bearer) {
  int64_t id = 0;
  std::string secret;
  Status parsed = ParseToken(bearer, &id, &secret);
  if (!parsed.ok())
    return Status::Unauthenticated("the bearer token is malformed: " + parsed.message());
  StatusOr<storage::TokenRecord> record = core_->store().GetToken(id);
  const Status unknown = Status::Unauthenticated("unknown token (wrong secret or no such token)");
  if (!record.ok())
    return record.status().code() == StatusCode::kNotFound ? unknown : record.status();
  if (!ConstantTimeEqual(Sha256(secret), record->secret_sha256)) return unknown;
  if (record->revoked_ns != 0) {
    return Status::Unauthenticated("token '" + record->name +
                                   "' was revoked; ask an admin for a new one");
  }
  Principal p;
  p.name = record->name;
  p.robot_id = record->robot_id;
  p.credential = "token";
  p.maps = SplitMapIds(record->maps);  // stored sorted
  if (!ParseRole(record->role, &p.role))
    return Status::Internal("token '" + record->name + "' has unknown role");
  tokens_exist_ = true;
  return p;
}

StatusOr<Principal> AccessControl::Authenticate(const grpc::ServerContextBase& context) {
  const auto& metadata = context.client_metadata();
  if (auto it = metadata.find("authorization"); it != metadata.end()) {
    const std::string_view value = View(it->second);
    if (value.substr(0, sizeof(kBearer) - 1) != kBearer) {
      return Status::Unauthenticated("the authorization metadata must be 'Bearer <token>'");
    }
    StatusOr<Principal> p = FromToken(value.substr(sizeof(kBearer) - 1));
    if (!p.ok()) {
      Log(LogLevel::kWarn, "auth_refused",
          {{"peer", context.peer()}, {"error", p.status().ToString()}});
    } else {
      p->peer = context.peer();
    }
    return p;
  }
  if (options_.client_certs) {
    // The TLS layer has verified the chain against tls_client_ca already.
    std::shared_ptr<const grpc::AuthContext> auth = context.auth_context();
    if (auth && auth->IsPeerAuthenticated()) {
      for (const grpc::string_ref& cn : auth->FindPropertyValues("x509_common_name")) {
        Principal p;
        p.name = std::string(View(cn));
        p.role = Role::kRobot;
        p.robot_id = p.name;
        p.credential = "certificate";
        p.peer = context.peer();
        if (ValidTokenName(p.robot_id)) return p;
        return Status::Unauthenticated("the client certificate's CN '" + p.name.substr(0, 64) +
                                       "' is not a robot id ([A-Za-z0-9_.-], 1-128 characters)");
      }
    }
  }
  StatusOr<bool> required = Required();
  if (!required.ok()) return required.status();
  if (!*required) {
    Principal anonymous = AnonymousOperator();
    anonymous.peer = context.peer();
    return anonymous;
  }
  return Status::Unauthenticated(
      "authentication required: send 'authorization: Bearer <token>' metadata (mapctl --token or "
      "$MAPD_TOKEN)" +
      std::string(options_.client_certs ? " or a client certificate signed by tls_client_ca" : ""));
}

StatusOr<Principal> AccessControl::AuthenticateHeader(const std::string* authorization,
                                                      const std::string& peer) {
  if (authorization != nullptr) {
    const std::string_view value = *authorization;
    StatusOr<Principal> p = value.substr(0, sizeof(kBearer) - 1) != kBearer
                                ? StatusOr<Principal>(Status::Unauthenticated(
                                      "the Authorization header must be 'Bearer <token>'"))
                                : FromToken(value.substr(sizeof(kBearer) - 1));
    if (!p.ok()) {
      Log(LogLevel::kWarn, "auth_refused",
          {{"peer", peer}, {"via", "http"}, {"error", p.status().ToString()}});
    } else {
      p->peer = peer;
    }
    return p;
  }
  StatusOr<bool> required = Required();
  if (!required.ok()) return required.status();
  if (!*required) {
    Principal anonymous = AnonymousOperator();
    anonymous.peer = peer;
    return anonymous;
  }
  return Status::Unauthenticated(
      "authentication required: send an 'Authorization: Bearer <token>' header");
}

StatusOr<Principal> AccessControl::Admit(const grpc::ServerContextBase& context,
                                         Permission permission, const std::string& action,
                                         const std::string& robot, const std::string& target) {
  StatusOr<Principal> p = Authenticate(context);
  if (!p.ok()) return p.status();
  MAPD_RETURN_IF_ERROR(Check(*p, permission, action, robot,
                             !target.empty() ? target
                             : robot.empty() ? ""
                                             : "robot " + robot));
  return p;
}

Status AccessControl::Check(const Principal& principal, Permission permission,
                            const std::string& action, const std::string& robot,
                            const std::string& target) {
  Status s = Authorize(principal, permission, action, robot);
  if (!s.ok() && IsWrite(permission)) AuditDenied(principal, action, target, s);
  return s;
}

Status AccessControl::CheckMap(const Principal& principal, const std::string& map,
                               const std::string& action) {
  Status s = AuthorizeMap(principal, map, action);
  if (!s.ok()) AuditDenied(principal, action, "map " + map, s);
  return s;
}

void AccessControl::CheckAsync(const Principal& principal, Permission permission,
                               const std::string& action, const std::string& robot,
                               const std::string& target, std::function<void(const Status&)> done) {
  Status s = Authorize(principal, permission, action, robot);
  if (s.ok() || !IsWrite(permission)) {
    done(s);
    return;
  }
  LogDenied(principal, action, target);
  AuditDeniedAsync(Entry(principal, action, target, "denied: " + s.message()),
                   [done = std::move(done), s] { done(s); });
}

void AccessControl::LogDenied(const Principal& principal, const std::string& action,
                              const std::string& target) {
  Log(LogLevel::kWarn, "permission_denied",
      {{"who", principal.name},
       {"role", RoleName(principal.role)},
       {"action", action},
       {"target", target}});
}

void AccessControl::AuditDenied(const Principal& principal, const std::string& action,
                                const std::string& target, const Status& why) {
  LogDenied(principal, action, target);
  storage::AuditEntry e = Entry(principal, action, target, "denied: " + why.message());
  if (!denials_->Admit(e, e.time_ns)) return;
  Status s =
      core_->ExecuteWrite([&e](storage::WriteTransaction* txn) { return txn->AppendAudit(e); });
  if (!s.ok()) Log(LogLevel::kWarn, "audit_failed", {{"action", action}, {"error", s.ToString()}});
}

storage::AuditEntry AccessControl::Entry(const Principal& principal, const std::string& action,
                                         const std::string& target, const std::string& result) {
  storage::AuditEntry e;
  e.time_ns = UnixNowNs();
  e.who = principal.name;
  e.role = principal.anonymous ? "anonymous" : RoleName(principal.role);
  e.action = action;
  e.target = target;
  e.result = result;
  e.peer = principal.peer;
  e.credential = principal.credential;
  return e;
}

AccessControl::AccessControl(Core* core, AuthOptions options)
    : core_(core),
      options_(options),
      denials_(options.denials ? options.denials
                               : std::make_shared<DenialAuditLimiter>(options.denials_per_minute)) {
}

void AccessControl::AuditDeniedAsync(storage::AuditEntry entry, std::function<void()> done) {
  if (!denials_->Admit(entry, entry.time_ns)) {
    done();
    return;
  }
  AuditAsync(std::move(entry), std::move(done));
}

void AccessControl::FlushDenials(bool all) {
  std::vector<storage::AuditEntry> rows = denials_->TakeSummaries(UnixNowNs(), all);
  if (rows.empty()) return;
  const Status s = core_->ExecuteWrite([&rows](storage::WriteTransaction* txn) {
    for (const storage::AuditEntry& e : rows) MAPD_RETURN_IF_ERROR(txn->AppendAudit(e));
    return Status::Ok();
  });
  if (!s.ok())
    Log(LogLevel::kWarn, "audit_failed", {{"action", "denials"}, {"error", s.ToString()}});
}

void AccessControl::AuditAsync(storage::AuditEntry entry, std::function<void()> done) {
  std::string action = entry.action;
  core_->SubmitWrite(
      [entry = std::move(entry)](storage::WriteTransaction* txn) {
        return txn->AppendAudit(entry);
      },
      [done = std::move(done), action = std::move(action)](const Status& s) {
        if (!s.ok())
          Log(LogLevel::kWarn, "audit_failed", {{"action", action}, {"error", s.ToString()}});
        done();
      });
}

}  // namespace mapd::service
