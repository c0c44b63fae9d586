// mapctl token create|list|revoke, mapctl audit, mapctl whoami (docs/security.md).
#include <cstdio>
#include <ctime>
#include <string>

#include "client/commands.h"

namespace mapd::client {
namespace {

namespace pb = mapserver::v1;

const char kTokenHelp[] =
    "Usage: mapctl [--token ADMIN_TOKEN] token create --name NAME --role ROLE [--robot ROBOT_ID]\n"
    "       mapctl [--token ADMIN_TOKEN] token list\n"
    "       mapctl [--token ADMIN_TOKEN] token revoke ID\n"
    "Manages bearer tokens (needs an admin token; the first one comes from\n"
    "`mapd token create --db FILE --role admin --name NAME`).\n"
    "  ROLE: reader (reads everything), robot (writes its own robot id; needs --robot),\n"
    "        operator (reads, writes, merges, deletes, reads the audit log), admin.\n"
    "create prints the secret token once on stdout; the server keeps only its hash.\n";

const char kAuditHelp[] =
    "Usage: mapctl audit [--limit N]\n"
    "The audit log, newest first (default 100 entries, at most 10000): uploads, merges,\n"
    "deletes, token changes and refused writes, with who did them. Operator or admin.\n";

const char kWhoAmIHelp[] =
    "Usage: mapctl whoami\nWho the server takes this caller for: name, role, robot id.\n";

const char* RoleName(pb::Role r) {
  switch (r) {
    case pb::ROLE_READER: return "reader";
    case pb::ROLE_ROBOT: return "robot";
    case pb::ROLE_OPERATOR: return "operator";
    case pb::ROLE_ADMIN: return "admin";
    default: return "?";
  }
}

bool ParseRole(const std::string& s, pb::Role* out) {
  for (pb::Role r : {pb::ROLE_READER, pb::ROLE_ROBOT, pb::ROLE_OPERATOR, pb::ROLE_ADMIN}) {
    if (s == RoleName(r)) return *out = r, true;
  }
  return false;
}

std::string Utc(int64_t ns) {
  if (ns == 0) return "-";
  const std::time_t t = static_cast<std::time_t>(ns / 1000000000);
  std::tm tm{};
  gmtime_r(&t, &tm);
  char buf[32];
  std::strftime(buf, sizeof(buf), "%Y-%m-%dT%H:%M:%SZ", &tm);
  return buf;
}

void PrintTokens(const pb::ListTokensResponse& r) {
  std::printf("%-5s %-24s %-9s %-16s %-20s %-20s %s\n", "ID", "NAME", "ROLE", "ROBOT", "CREATED", "BY", "REVOKED");
  for (const pb::TokenInfo& t : r.tokens()) {
    std::printf("%-5llu %-24s %-9s %-16s %-20s %-20s %s\n", static_cast<unsigned long long>(t.id()), t.name().c_str(),
                RoleName(t.role()), t.robot_id().empty() ? "-" : t.robot_id().c_str(), Utc(t.created_ns()).c_str(),
                t.created_by().c_str(), Utc(t.revoked_ns()).c_str());
  }
}

int TokenCreate(const Context& ctx, const Args& flags) {
  pb::CreateTokenRequest request;
  request.set_name(flags.Get("--name"));
  request.set_robot_id(flags.Get("--robot"));
  pb::Role role = pb::ROLE_UNSPECIFIED;
  if (!ParseRole(flags.Get("--role"), &role)) {
    return UsageError("token", "--role must be reader, robot, operator or admin, got '" + flags.Get("--role") + "'");
  }
  if (request.name().empty()) return UsageError("token", "create needs --name NAME");
  request.set_role(role);
  pb::CreateTokenResponse response;
  auto call = ctx.NewCallContext();
  const grpc::Status status = ctx.stub->CreateToken(call.get(), request, &response);
  if (!status.ok()) return ReportRpcError(ctx, "token create", status);
  std::fprintf(stderr, "created token %llu '%s' (role %s%s); the secret is shown only now:\n",
               static_cast<unsigned long long>(response.info().id()), response.info().name().c_str(),
               RoleName(response.info().role()),
               response.info().robot_id().empty() ? "" : (", robot " + response.info().robot_id()).c_str());
  std::printf("%s\n", response.token().c_str());
  return kExitOk;
}

}  // namespace

int RunToken(const Context& ctx, const CommandArgs& args) {
  Args flags;
  const std::vector<FlagSpec> specs = {{"--name", true}, {"--role", true}, {"--robot", true}};
  if (int rc = ParseCommandArgs("token", kTokenHelp, args, specs, &flags); rc != kContinue) return rc;
  const auto& pos = flags.positionals();
  const std::string verb = pos.empty() ? "" : pos[0];
  if (verb == "create") {
    if (pos.size() != 1) return UsageError("token", "create takes no positional arguments");
    return TokenCreate(ctx, flags);
  }
  if (flags.Has("--name") || flags.Has("--role") || flags.Has("--robot")) {
    return UsageError("token", "--name, --role and --robot are for 'token create'");
  }
  if (verb == "list" && pos.size() == 1) {
    pb::ListTokensResponse response;
    auto call = ctx.NewCallContext();
    const grpc::Status status = ctx.stub->ListTokens(call.get(), pb::ListTokensRequest(), &response);
    if (!status.ok()) return ReportRpcError(ctx, "token list", status);
    PrintTokens(response);
    return kExitOk;
  }
  if (verb == "revoke" && pos.size() == 2) {
    pb::RevokeTokenRequest request;
    uint64_t id = 0;
    if (!ParseUint(pos[1], &id) || id == 0) return UsageError("token", "revoke wants a token ID, got '" + pos[1] + "'");
    request.set_id(id);
    pb::RevokeTokenResponse response;
    auto call = ctx.NewCallContext();
    const grpc::Status status = ctx.stub->RevokeToken(call.get(), request, &response);
    if (!status.ok()) return ReportRpcError(ctx, "token revoke", status);
    std::printf("revoked token %llu '%s'\n", static_cast<unsigned long long>(id), response.info().name().c_str());
    return kExitOk;
  }
  return UsageError("token", "use 'token create --name N --role R', 'token list' or 'token revoke ID'");
}

int RunAudit(const Context& ctx, const CommandArgs& args) {
  Args flags;
  if (int rc = ParseCommandArgs("audit", kAuditHelp, args, {{"--limit", true}}, &flags); rc != kContinue) return rc;
  if (!flags.positionals().empty()) return UsageError("audit", "unexpected argument '" + flags.positionals()[0] + "'");
  uint64_t limit = 100;
  if (flags.Has("--limit") && (!ParseUint(flags.Get("--limit"), &limit) || limit == 0 || limit > 10000)) {
    return UsageError("audit", "--limit wants 1..10000, got '" + flags.Get("--limit") + "'");
  }
  pb::ListAuditRequest request;
  request.set_limit(static_cast<uint32_t>(limit));
  pb::ListAuditResponse response;
  auto call = ctx.NewCallContext();
  const grpc::Status status = ctx.stub->ListAudit(call.get(), request, &response);
  if (!status.ok()) return ReportRpcError(ctx, "audit", status);
  std::printf("%-6s %-20s %-20s %-9s %-14s %-40s %s\n", "ID", "TIME", "WHO", "ROLE", "ACTION", "TARGET", "RESULT");
  for (const pb::AuditEntry& e : response.entries()) {
    std::printf("%-6llu %-20s %-20s %-9s %-14s %-40s %s\n", static_cast<unsigned long long>(e.id()),
                Utc(e.time_ns()).c_str(), e.who().c_str(), e.role().c_str(), e.action().c_str(), e.target().c_str(),
                e.result().c_str());
  }
  return kExitOk;
}

int RunWhoAmI(const Context& ctx, const CommandArgs& args) {
  Args flags;
  if (int rc = ParseCommandArgs("whoami", kWhoAmIHelp, args, {}, &flags); rc != kContinue) return rc;
  pb::WhoAmIResponse response;
  auto call = ctx.NewCallContext();
  const grpc::Status status = ctx.stub->WhoAmI(call.get(), pb::WhoAmIRequest(), &response);
  if (!status.ok()) return ReportRpcError(ctx, "whoami", status);
  std::printf("%s (role %s%s)%s\n", response.name().c_str(), RoleName(response.role()),
              response.robot_id().empty() ? "" : (", robot " + response.robot_id()).c_str(),
              response.anonymous() ? ": the open mode, no credential needed" : "");
  return kExitOk;
}

}  // namespace mapd::client
