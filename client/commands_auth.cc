// mapctl token create|list|revoke, mapctl audit, mapctl whoami (docs/security.md).
#include <cstdio>
#include <cstring>
#include <ctime>
#include <string>

#include "client/commands.h"
#include "client/format.h"
#include "client/text_util.h"

namespace mapd::client {
namespace {

namespace pb = mapserver::v1;

struct CreateOptions {
  std::string name;
  std::string role;
  std::string robot;
  std::vector<std::string> maps;
};

struct RevokeOptions {
  uint64_t id = 0;
};

struct AuditOptions {
  uint32_t limit = 100;
  bool json = false;
};

struct NoOptions {};

const char* RoleName(pb::Role r) {
  switch (r) {
    case pb::ROLE_READER:
      return "reader";
    case pb::ROLE_ROBOT:
      return "robot";
    case pb::ROLE_OPERATOR:
      return "operator";
    case pb::ROLE_ADMIN:
      return "admin";
    default:
      return "?";
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
  std::printf("%-5s %-24s %-9s %-16s %-20s %-20s %-20s %s\n", "ID", "NAME", "ROLE", "ROBOT",
              "CREATED", "BY", "REVOKED", "MAPS");
  for (const pb::TokenInfo& t : r.tokens()) {
    std::string maps;
    for (const std::string& m : t.maps()) maps += (maps.empty() ? "" : ",") + Visible(m);
    std::printf("%-5llu %-24s %-9s %-16s %-20s %-20s %-20s %s\n",
                static_cast<unsigned long long>(t.id()), Visible(t.name()).c_str(),
                RoleName(t.role()), t.robot_id().empty() ? "-" : Visible(t.robot_id()).c_str(),
                Utc(t.created_ns()).c_str(), Visible(t.created_by()).c_str(),
                Utc(t.revoked_ns()).c_str(), maps.empty() ? "(every map)" : maps.c_str());
  }
}

int RunTokenCreate(const Context& ctx, const CreateOptions& flags) {
  pb::CreateTokenRequest request;
  request.set_name(flags.name);
  request.set_robot_id(flags.robot);
  for (const std::string& map : flags.maps) request.add_maps(map);
  pb::Role role = pb::ROLE_UNSPECIFIED;
  ParseRole(flags.role, &role);  // checked by the parser
  request.set_role(role);
  pb::CreateTokenResponse response;
  auto call = ctx.NewCallContext();
  const grpc::Status status = ctx.stub->CreateToken(call.get(), request, &response);
  if (!status.ok()) return ReportRpcError(ctx, "token create", status);
  std::fprintf(
      stderr, "created token %llu '%s' (role %s%s); the secret is shown only now:\n",
      static_cast<unsigned long long>(response.info().id()), response.info().name().c_str(),
      RoleName(response.info().role()),
      response.info().robot_id().empty() ? "" : (", robot " + response.info().robot_id()).c_str());
  std::printf("%s\n", response.token().c_str());
  return kExitOk;
}

int RunTokenList(const Context& ctx, const NoOptions& /*flags*/) {
  pb::ListTokensResponse response;
  auto call = ctx.NewCallContext();
  const grpc::Status status = ctx.stub->ListTokens(call.get(), pb::ListTokensRequest(), &response);
  if (!status.ok()) return ReportRpcError(ctx, "token list", status);
  PrintTokens(response);
  return kExitOk;
}

int RunTokenRevoke(const Context& ctx, const RevokeOptions& flags) {
  pb::RevokeTokenRequest request;
  request.set_id(flags.id);
  pb::RevokeTokenResponse response;
  auto call = ctx.NewCallContext();
  const grpc::Status status = ctx.stub->RevokeToken(call.get(), request, &response);
  if (!status.ok()) return ReportRpcError(ctx, "token revoke", status);
  std::printf("revoked token %llu '%s'\n", static_cast<unsigned long long>(flags.id),
              response.info().name().c_str());
  return kExitOk;
}

// How and from where: "token 10.0.0.7:41234" ("-" for rows from before mapd
// recorded it).
std::string Via(const pb::AuditEntry& e) {
  std::string peer = e.peer();
  for (const char* scheme : {"ipv4:", "ipv6:"}) {
    if (peer.rfind(scheme, 0) == 0) peer = peer.substr(std::strlen(scheme));
  }
  std::string via = e.credential().empty() ? "-" : e.credential();
  if (!peer.empty()) via += " " + peer;
  return Visible(via);
}

int RunAudit(const Context& ctx, const AuditOptions& flags) {
  pb::ListAuditRequest request;
  request.set_limit(flags.limit);
  pb::ListAuditResponse response;
  auto call = ctx.NewCallContext();
  const grpc::Status status = ctx.stub->ListAudit(call.get(), request, &response);
  if (!status.ok()) return ReportRpcError(ctx, "audit", status);
  if (flags.json) {  // for scripts; JSON escapes every control character
    std::fputs(MessageToJson(response).c_str(), stdout);
    return kExitOk;
  }
  std::printf("%-6s %-20s %-20s %-9s %-28s %-14s %-40s %s\n", "ID", "TIME", "WHO", "ROLE", "VIA",
              "ACTION", "TARGET", "RESULT");
  for (const pb::AuditEntry& e : response.entries()) {
    std::printf("%-6llu %-20s %-20s %-9s %-28s %-14s %-40s %s\n",
                static_cast<unsigned long long>(e.id()), Utc(e.time_ns()).c_str(),
                Visible(e.who()).c_str(), Visible(e.role()).c_str(), Via(e).c_str(),
                Visible(e.action()).c_str(), Visible(e.target()).c_str(),
                Visible(e.result()).c_str());
  }
  return kExitOk;
}

int RunWhoAmI(const Context& ctx, const NoOptions& /*flags*/) {
  pb::WhoAmIResponse response;
  auto call = ctx.NewCallContext();
  const grpc::Status status = ctx.stub->WhoAmI(call.get(), pb::WhoAmIRequest(), &response);
  if (!status.ok()) return ReportRpcError(ctx, "whoami", status);
  std::printf("%s (role %s%s)%s\n", response.name().c_str(), RoleName(response.role()),
              response.robot_id().empty() ? "" : (", robot " + response.robot_id()).c_str(),
              response.anonymous() ? ": the open mode, no credential needed" : "");
  return kExitOk;
}

}  // namespace

void AddAuthCommands(CLI::App* app, Action* action) {
  CLI::App* token =
      app->add_subcommand("token", "token create|list|revoke: manage bearer tokens (admin)");
  token->require_subcommand(1);
  token->footer(
      "Manages bearer tokens (needs an admin token, --token before the command; the first one\n"
      "comes from `mapd token create --db FILE --role admin --name NAME`).\n"
      "ROLE: reader (reads everything), robot (writes its own robot id; needs --robot),\n"
      "operator (reads, writes, merges, deletes, reads the audit log), admin.");
  CLI::App* create = token->add_subcommand("create",
                                           "create a token; prints the secret once on stdout "
                                           "(the server keeps only its hash)");
  auto c = BindCommand(create, action, RunTokenCreate);
  create->add_option("--name", c->name, "what the token is for")->required();
  create->add_option("--role", c->role, "reader, robot, operator or admin")
      ->required()
      ->check(CLI::IsMember({"reader", "robot", "operator", "admin"}));
  create->add_option("--robot", c->robot, "the robot id a robot token may write");
  create->add_option("--maps", c->maps, "ID,...: the maps it may act on (default: every map)")
      ->delimiter(',');
  CLI::App* list = token->add_subcommand("list", "list the tokens");
  BindCommand(list, action, RunTokenList);
  CLI::App* revoke = token->add_subcommand("revoke", "revoke a token");
  revoke
      ->add_option("ID", BindCommand(revoke, action, RunTokenRevoke)->id,
                   "the token's id (token list)")
      ->required()
      ->check(PositiveId());

  CLI::App* audit = app->add_subcommand("audit", "the audit log, newest first (operator, admin)");
  audit->footer("Uploads, merges, deletes, token changes and refused writes, with who did them.");
  auto a = BindCommand(audit, action, RunAudit);
  audit->add_option("--limit", a->limit, "entries to show")
      ->capture_default_str()
      ->check(CLI::Range(1u, 10000u));
  audit->add_flag("--json", a->json,
                  "the entries as JSON (ListAuditResponse, .proto field names; ids and times "
                  "as numbers)");

  CLI::App* whoami =
      app->add_subcommand("whoami", "who the server takes this caller for: name, role, robot id");
  BindCommand(whoami, action, RunWhoAmI);
}

}  // namespace mapd::client
