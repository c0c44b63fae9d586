#include "service/auth_service.h"

#include "common/clock.h"
#include "service/log.h"
#include "service/map_id.h"
#include "service/status_mapping.h"
#include "service/token.h"

namespace mapd::service {
namespace {

namespace pb = mapserver::v1;

constexpr uint32_t kDefaultAuditLimit = 100;
constexpr uint32_t kMaxAuditLimit = 10000;

pb::Role RoleToProto(Role r) {
  switch (r) {
    case Role::kReader:
      return pb::ROLE_READER;
    case Role::kRobot:
      return pb::ROLE_ROBOT;
    case Role::kOperator:
      return pb::ROLE_OPERATOR;
    case Role::kAdmin:
      return pb::ROLE_ADMIN;
  }
  return pb::ROLE_UNSPECIFIED;
}

bool RoleFromProto(pb::Role r, Role* out) {
  switch (r) {
    case pb::ROLE_READER:
      *out = Role::kReader;
      return true;
    case pb::ROLE_ROBOT:
      *out = Role::kRobot;
      return true;
    case pb::ROLE_OPERATOR:
      *out = Role::kOperator;
      return true;
    case pb::ROLE_ADMIN:
      *out = Role::kAdmin;
      return true;
    default:
      return false;
  }
}

void TokenToProto(const storage::TokenRecord& t, pb::TokenInfo* out) {
  Role role = Role::kReader;
  out->set_id(static_cast<uint64_t>(t.id));
  out->set_name(t.name);
  out->set_role(ParseRole(t.role, &role) ? RoleToProto(role) : pb::ROLE_UNSPECIFIED);
  out->set_robot_id(t.robot_id);
  out->set_created_ns(t.created_ns);
  out->set_created_by(t.created_by);
  out->set_revoked_ns(t.revoked_ns);
  for (const std::string& map : SplitMapIds(t.maps)) out->add_maps(map);
}

std::string TokenTarget(int64_t id, const std::string& name) {
  return "token " + std::to_string(id) + " '" + name + "'";
}

}  // namespace

grpc::Status AuthService::CreateToken(const grpc::ServerContextBase& context,
                                      const pb::CreateTokenRequest& request,
                                      pb::CreateTokenResponse* response) {
  StatusOr<Principal> admin = access_->Admit(
      context, Permission::kManageTokens, "CreateToken", "",
      "token '" + request.name().substr(0, 128) + "' " + pb::Role_Name(request.role()));
  if (!admin.ok()) return ToGrpcStatus(admin.status());
  NewToken t;
  if (!RoleFromProto(request.role(), &t.role)) {
    return grpc::Status(grpc::StatusCode::INVALID_ARGUMENT,
                        "role is required: ROLE_READER, ROLE_ROBOT, ROLE_OPERATOR or ROLE_ADMIN");
  }
  t.name = request.name();
  t.robot_id = request.robot_id();
  t.created_by = admin->name;
  t.maps.assign(request.maps().begin(), request.maps().end());
  IssuedToken issued;
  Status s = core_->ExecuteWrite([&](storage::WriteTransaction* txn) {
    StatusOr<IssuedToken> r = IssueToken(t, UnixNowNs(), txn);
    if (!r.ok()) return r.status();
    issued = std::move(r).value();
    return txn->AppendAudit(
        AccessControl::Entry(*admin, "CreateToken",
                             TokenTarget(issued.record.id, t.name) + " role " + RoleName(t.role) +
                                 (t.robot_id.empty() ? "" : " robot " + t.robot_id) +
                                 (issued.record.maps.empty() ? "" : " maps " + issued.record.maps),
                             "ok"));
  });
  if (!s.ok()) return ToGrpcStatus(s);
  Log(LogLevel::kInfo, "token_created",
      {{"id", std::to_string(issued.record.id)},
       {"name", t.name},
       {"role", RoleName(t.role)},
       {"by", admin->name}});
  TokenToProto(issued.record, response->mutable_info());
  response->set_token(issued.token);
  return grpc::Status::OK;
}

grpc::Status AuthService::ListTokens(const grpc::ServerContextBase& context,
                                     pb::ListTokensResponse* response) {
  StatusOr<Principal> admin = access_->Admit(context, Permission::kManageTokens, "ListTokens");
  if (!admin.ok()) return ToGrpcStatus(admin.status());
  StatusOr<std::vector<storage::TokenRecord>> tokens = core_->store().ListTokens();
  if (!tokens.ok()) return ToGrpcStatus(tokens.status());
  for (const storage::TokenRecord& t : *tokens) TokenToProto(t, response->add_tokens());
  return grpc::Status::OK;
}

grpc::Status AuthService::RevokeToken(const grpc::ServerContextBase& context,
                                      const pb::RevokeTokenRequest& request,
                                      pb::RevokeTokenResponse* response) {
  StatusOr<Principal> admin = access_->Admit(context, Permission::kManageTokens, "RevokeToken", "",
                                             "token " + std::to_string(request.id()));
  if (!admin.ok()) return ToGrpcStatus(admin.status());
  if (request.id() == 0) return grpc::Status(grpc::StatusCode::INVALID_ARGUMENT, "id is required");
  const int64_t id = static_cast<int64_t>(request.id());
  StatusOr<storage::TokenRecord> before = core_->store().GetToken(id);
  if (!before.ok()) return ToGrpcStatus(before.status());
  Status s = core_->ExecuteWrite([&](storage::WriteTransaction* txn) {
    MAPD_RETURN_IF_ERROR(txn->RevokeToken(id, UnixNowNs()));
    return txn->AppendAudit(
        AccessControl::Entry(*admin, "RevokeToken", TokenTarget(id, before->name), "ok"));
  });
  if (!s.ok()) return ToGrpcStatus(s);
  Log(LogLevel::kInfo, "token_revoked",
      {{"id", std::to_string(id)}, {"name", before->name}, {"by", admin->name}});
  StatusOr<storage::TokenRecord> after = core_->store().GetToken(id);
  if (!after.ok()) return ToGrpcStatus(after.status());
  TokenToProto(*after, response->mutable_info());
  return grpc::Status::OK;
}

grpc::Status AuthService::ListAudit(const grpc::ServerContextBase& context,
                                    const pb::ListAuditRequest& request,
                                    pb::ListAuditResponse* response) {
  StatusOr<Principal> p = access_->Admit(context, Permission::kReadAudit, "ListAudit");
  if (!p.ok()) return ToGrpcStatus(p.status());
  if (request.limit() > kMaxAuditLimit) {
    return grpc::Status(
        grpc::StatusCode::INVALID_ARGUMENT,
        "limit " + std::to_string(request.limit()) + " is above " + std::to_string(kMaxAuditLimit));
  }
  const uint32_t limit = request.limit() == 0 ? kDefaultAuditLimit : request.limit();
  StatusOr<std::vector<storage::AuditEntry>> entries =
      core_->store().ListAudit(static_cast<int>(limit));
  if (!entries.ok()) return ToGrpcStatus(entries.status());
  for (const storage::AuditEntry& e : *entries) {
    pb::AuditEntry* out = response->add_entries();
    out->set_id(static_cast<uint64_t>(e.id));
    out->set_time_ns(e.time_ns);
    out->set_who(e.who);
    out->set_role(e.role);
    out->set_action(e.action);
    out->set_target(e.target);
    out->set_result(e.result);
    out->set_peer(e.peer);
    out->set_credential(e.credential);
  }
  return grpc::Status::OK;
}

grpc::Status AuthService::WhoAmI(const grpc::ServerContextBase& context,
                                 pb::WhoAmIResponse* response) {
  StatusOr<Principal> p = access_->Authenticate(context);
  if (!p.ok()) return ToGrpcStatus(p.status());
  response->set_name(p->name);
  response->set_role(RoleToProto(p->role));
  response->set_robot_id(p->robot_id);
  response->set_anonymous(p->anonymous);
  return grpc::Status::OK;
}

}  // namespace mapd::service
