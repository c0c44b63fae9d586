#include "token_command.h"

#include <cstdio>
#include <map>

#include "common/clock.h"
#include "service/auth.h"
#include "service/token.h"
#include "storage/store.h"

namespace mapd {
namespace {

constexpr char kUsage[] =
    "usage: mapd token create --db FILE --role ROLE --name NAME [--robot ROBOT_ID]\n"
    "       mapd token list   --db FILE\n"
    "       mapd token revoke --db FILE --id ID\n\n"
    "Manages mapd's bearer tokens directly in the database file (no server needed;\n"
    "it may run). ROLE: reader, robot (needs --robot), operator, admin. create prints\n"
    "the secret token once on stdout; only its SHA-256 is stored. Then use\n"
    "`mapctl --token ... token create|list|revoke` with an admin token.\n";

int Usage(const std::string& message) {
  std::fprintf(stderr, "mapd token: %s\n\n%s", message.c_str(), kUsage);
  return 2;
}

int Fail(const Status& s) {
  std::fprintf(stderr, "mapd token: %s\n", s.ToString().c_str());
  return 1;
}

// Runs `write` in one committed transaction.
template <typename Fn>
Status Write(storage::Store& store, Fn write) {
  StatusOr<std::unique_ptr<storage::WriteTransaction>> txn = store.BeginWrite();
  if (!txn.ok()) return txn.status();
  MAPD_RETURN_IF_ERROR(write(txn->get()));
  return (*txn)->Commit();
}

storage::AuditEntry OfflineAudit(const std::string& action, const std::string& target) {
  storage::AuditEntry e;
  e.time_ns = UnixNowNs();
  e.who = "mapd token (offline)";
  e.role = "file access";
  e.action = action;
  e.target = target;
  e.result = "ok";
  return e;
}

}  // namespace

int RunTokenCommand(const std::vector<std::string>& args) {
  if (args.empty() || args[0] == "--help" || args[0] == "-h") {
    std::fputs(kUsage, args.empty() ? stderr : stdout);
    return args.empty() ? 2 : 0;
  }
  const std::string verb = args[0];
  std::map<std::string, std::string> flags;
  for (size_t i = 1; i < args.size(); ++i) {
    const std::string& a = args[i];
    if (a == "--help" || a == "-h") return std::fputs(kUsage, stdout), 0;
    if (a.rfind("--", 0) != 0) return Usage("unexpected argument '" + a + "'");
    const size_t eq = a.find('=');
    if (eq != std::string::npos) {
      flags[a.substr(2, eq - 2)] = a.substr(eq + 1);
    } else if (i + 1 < args.size()) {
      flags[a.substr(2)] = args[++i];
    } else {
      return Usage(a + " needs a value");
    }
  }
  const std::map<std::string, std::vector<std::string>> known = {
      {"create", {"db", "role", "name", "robot"}}, {"list", {"db"}}, {"revoke", {"db", "id"}}};
  auto spec = known.find(verb);
  if (spec == known.end()) return Usage("unknown verb '" + verb + "' (create, list, revoke)");
  for (const auto& [k, v] : flags) {
    bool ok = false;
    for (const std::string& allowed : spec->second) ok = ok || k == allowed;
    if (!ok) return Usage("'" + verb + "' takes no --" + k);
  }
  if (flags["db"].empty()) return Usage("--db FILE is required (the database mapd serves)");

  StatusOr<std::unique_ptr<storage::Store>> store = storage::Store::Open(flags["db"], storage::StoreOptions{});
  if (!store.ok()) return Fail(store.status());

  if (verb == "create") {
    service::NewToken t;
    if (!service::ParseRole(flags["role"], &t.role)) {
      return Usage("--role must be reader, robot, operator or admin, got '" + flags["role"] + "'");
    }
    t.name = flags["name"];
    t.robot_id = flags["robot"];
    t.created_by = "mapd token (offline)";
    service::IssuedToken issued;
    Status s = Write(**store, [&](storage::WriteTransaction* txn) {
      StatusOr<service::IssuedToken> r = service::IssueToken(t, UnixNowNs(), txn);
      if (!r.ok()) return r.status();
      issued = std::move(r).value();
      return txn->AppendAudit(OfflineAudit("CreateToken", "token " + std::to_string(issued.record.id) + " '" +
                                                              t.name + "' role " + issued.record.role));
    });
    if (!s.ok()) return Fail(s);
    std::fprintf(stderr, "created token %lld '%s' (role %s%s); the secret is shown only now:\n",
                 static_cast<long long>(issued.record.id), t.name.c_str(), issued.record.role.c_str(),
                 t.robot_id.empty() ? "" : (", robot " + t.robot_id).c_str());
    std::printf("%s\n", issued.token.c_str());
    return 0;
  }
  if (verb == "list") {
    StatusOr<std::vector<storage::TokenRecord>> tokens = (*store)->ListTokens();
    if (!tokens.ok()) return Fail(tokens.status());
    std::printf("%-6s %-24s %-9s %-16s %s\n", "ID", "NAME", "ROLE", "ROBOT", "STATE");
    for (const auto& t : *tokens) {
      std::printf("%-6lld %-24s %-9s %-16s %s\n", static_cast<long long>(t.id), t.name.c_str(), t.role.c_str(),
                  t.robot_id.empty() ? "-" : t.robot_id.c_str(), t.revoked_ns ? "revoked" : "active");
    }
    return 0;
  }
  char* end = nullptr;
  const long long id = std::strtoll(flags["id"].c_str(), &end, 10);
  if (flags["id"].empty() || *end != '\0' || id <= 0) return Usage("--id wants a token id (see 'mapd token list')");
  Status s = Write(**store, [&](storage::WriteTransaction* txn) {
    MAPD_RETURN_IF_ERROR(txn->RevokeToken(id, UnixNowNs()));
    return txn->AppendAudit(OfflineAudit("RevokeToken", "token " + std::to_string(id)));
  });
  if (!s.ok()) return Fail(s);
  std::fprintf(stderr, "revoked token %lld\n", id);
  return 0;
}

}  // namespace mapd
