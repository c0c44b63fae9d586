#include "token_command.h"

#include <cstdio>
#include <limits>
#include <memory>

#include "common/clock.h"
#include "service/auth.h"
#include "service/file_modes.h"
#include "service/token.h"
#include "storage/postgres/store.h"
#include "storage/sqlite/store.h"
#include "storage/store.h"

namespace mapd {
namespace {

struct TokenOptions {
  std::string db;
  std::string store;  // PostgreSQL instead of a file
  std::string role;
  std::string name;
  std::string robot;
  std::vector<std::string> maps;
  int64_t id = 0;
};

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
  e.credential = "database file";
  return e;
}

StatusOr<std::unique_ptr<storage::Store>> Open(const TokenOptions& flags) {
  if (flags.db.empty() == flags.store.empty())
    return Status::InvalidArgument("give --db FILE or --store CONNINFO (one of them)");
  if (!flags.store.empty()) {
    // Tokens are the database's, whichever map: open the default map without
    // its lease, so that this works beside the mapd that serves it.
    MAPD_RETURN_IF_ERROR(storage::CheckConninfo(flags.store));
    storage::PgOwnership not_owner;
    not_owner.own = false;
    StatusOr<std::unique_ptr<storage::PgStore>> store =
        storage::PgStore::Open(flags.store, "default", storage::StoreOptions{}, not_owner);
    if (!store.ok()) return store.status();
    return std::unique_ptr<storage::Store>(std::move(store).value());
  }
  MAPD_RETURN_IF_ERROR(service::CheckDatabaseFileModes(flags.db));
  StatusOr<std::unique_ptr<storage::SqliteStore>> store =
      storage::SqliteStore::Open(flags.db, storage::StoreOptions{});
  if (!store.ok()) return store.status();
  return std::unique_ptr<storage::Store>(std::move(store).value());
}

int RunCreate(const TokenOptions& flags) {
  StatusOr<std::unique_ptr<storage::Store>> store = Open(flags);
  if (!store.ok()) return Fail(store.status());
  service::NewToken t;
  service::ParseRole(flags.role, &t.role);  // checked by the parser
  t.name = flags.name;
  t.robot_id = flags.robot;
  t.maps = flags.maps;
  t.created_by = "mapd token (offline)";
  service::IssuedToken issued;
  Status s = Write(**store, [&](storage::WriteTransaction* txn) {
    StatusOr<service::IssuedToken> r = service::IssueToken(t, UnixNowNs(), txn);
    if (!r.ok()) return r.status();
    issued = std::move(r).value();
    return txn->AppendAudit(
        OfflineAudit("CreateToken", "token " + std::to_string(issued.record.id) + " '" + t.name +
                                        "' role " + issued.record.role));
  });
  if (!s.ok()) return Fail(s);
  std::fprintf(stderr, "created token %lld '%s' (role %s%s); the secret is shown only now:\n",
               static_cast<long long>(issued.record.id), t.name.c_str(), issued.record.role.c_str(),
               t.robot_id.empty() ? "" : (", robot " + t.robot_id).c_str());
  std::printf("%s\n", issued.token.c_str());
  return 0;
}

int RunList(const TokenOptions& flags) {
  StatusOr<std::unique_ptr<storage::Store>> store = Open(flags);
  if (!store.ok()) return Fail(store.status());
  StatusOr<std::vector<storage::TokenRecord>> tokens = (*store)->ListTokens();
  if (!tokens.ok()) return Fail(tokens.status());
  std::printf("%-6s %-24s %-9s %-16s %-8s %s\n", "ID", "NAME", "ROLE", "ROBOT", "STATE", "MAPS");
  for (const auto& t : *tokens) {
    std::printf("%-6lld %-24s %-9s %-16s %-8s %s\n", static_cast<long long>(t.id), t.name.c_str(),
                t.role.c_str(), t.robot_id.empty() ? "-" : t.robot_id.c_str(),
                t.revoked_ns ? "revoked" : "active",
                t.maps.empty() ? "(every map)" : t.maps.c_str());
  }
  return 0;
}

int RunRevoke(const TokenOptions& flags) {
  StatusOr<std::unique_ptr<storage::Store>> store = Open(flags);
  if (!store.ok()) return Fail(store.status());
  Status s = Write(**store, [&](storage::WriteTransaction* txn) {
    MAPD_RETURN_IF_ERROR(txn->RevokeToken(flags.id, UnixNowNs()));
    return txn->AppendAudit(OfflineAudit("RevokeToken", "token " + std::to_string(flags.id)));
  });
  if (!s.ok()) return Fail(s);
  std::fprintf(stderr, "revoked token %lld\n", static_cast<long long>(flags.id));
  return 0;
}

}  // namespace

void AddTokenCommand(CLI::App* app, std::function<int()>* action) {
  CLI::App* token =
      app->add_subcommand("token", "create|list|revoke: manage tokens offline (docs/security.md)");
  token->require_subcommand(1);
  token->footer(
      "Manages mapd's bearer tokens directly in the database file (no server needed;\n"
      "it may run). create prints the secret token once on stdout; only its SHA-256 is\n"
      "stored. Then use `mapctl --token ... token create|list|revoke` with an admin token.");
  auto flags = std::make_shared<TokenOptions>();
  const auto add = [&](const char* name, const char* summary, int (*run)(const TokenOptions&)) {
    CLI::App* verb = token->add_subcommand(name, summary);
    CLI::Option* db =
        verb->add_option("--db", flags->db,
                         "the database file mapd serves (with --data-dir DIR: DIR/default.db, "
                         "which holds the tokens of every map)");
    verb->add_option("--store", flags->store,
                     "instead of --db: the PostgreSQL database mapd serves (--store of mapd)")
        ->excludes(db);
    verb->callback([flags, action, run] { *action = [flags, run] { return run(*flags); }; });
    return verb;
  };
  CLI::App* create = add("create", "create a token", RunCreate);
  create->add_option("--role", flags->role, "reader, robot (needs --robot), operator or admin")
      ->required()
      ->check(CLI::Validator(
          [](std::string& v) {
            service::Role role;
            return service::ParseRole(v, &role)
                       ? std::string()
                       : "must be reader, robot, operator or admin, got '" + v + "'";
          },
          "ROLE"));
  create->add_option("--name", flags->name, "what the token is for")->required();
  create->add_option("--robot", flags->robot, "the robot id a robot token may write");
  create->add_option("--maps", flags->maps, "ID,...: the maps it may act on (default: every map)")
      ->delimiter(',');
  add("list", "list the tokens", RunList);
  add("revoke", "revoke a token", RunRevoke)
      ->add_option("--id", flags->id, "the token's id (see 'mapd token list')")
      ->required()
      ->check(CLI::Range(int64_t{1}, std::numeric_limits<int64_t>::max()));
}

}  // namespace mapd
