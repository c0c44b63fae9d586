#include "migrate_command.h"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <memory>
#include <optional>

#include "common/clock.h"
#include "service/file_modes.h"
#include "service/map_directory.h"
#include "service/map_id.h"
#include "service/map_settings.h"
#include "storage/map_copy.h"
#include "storage/postgres/map_catalog.h"
#include "storage/postgres/map_lease.h"
#include "storage/postgres/store.h"
#include "storage/sqlite/store.h"

namespace mapd {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

struct MigrateOptions {
  std::string from;
  std::string from_map = service::kDefaultMapId;
  std::string to;
  std::string map;
  bool with_tokens = false;
};

// The target map's lease: long enough that a slow commit of a large submap
// never loses it, short enough that a copier that died frees the map soon.
constexpr double kLeaseTtlS = 60;
constexpr double kRenewEveryS = 10;

bool IsConninfo(const std::string& s) {
  return s.rfind("postgresql://", 0) == 0 || s.rfind("postgres://", 0) == 0 ||
         s.find('=') != std::string::npos;
}

int MigrateFailed(const Status& s) {
  std::fprintf(stderr, "mapd migrate: %s\n", s.ToString().c_str());
  return 1;
}

// The instance name the copy holds leases under.
storage::PgInstance Importer() {
  storage::PgInstance me = storage::DefaultPgInstance();
  me.name = "mapd migrate " + me.name;
  return me;
}

// The leases a copy holds (a PostgreSQL source's and target's), renewed
// between its commits on connections of their own.
class Leases {
 public:
  Status Add(const std::string& conninfo, const storage::MapLease& lease) {
    StatusOr<storage::PgConnection> conn = storage::PgConnection::Connect(conninfo);
    if (!conn.ok()) return conn.status();
    held_.push_back({std::move(conn).value(), lease});
    return Status::Ok();
  }
  Status Renew() {
    for (Held& h : held_) MAPD_RETURN_IF_ERROR(storage::RenewMapLease(h.conn, h.lease, kLeaseTtlS));
    return Status::Ok();
  }

 private:
  struct Held {
    storage::PgConnection conn;
    storage::MapLease lease;
  };
  std::vector<Held> held_;
};

// An open source: its store, and what keeps others off it meanwhile.
struct Source {
  service::DatabaseLock lock;  // a file's: released after the store closed
  std::unique_ptr<storage::Store> store;
  service::MapSettings settings;  // the map's own (map_settings.h)
};

StatusOr<Source> OpenSource(const MigrateOptions& o, Leases* leases) {
  Source src;
  if (IsConninfo(o.from)) {
    MAPD_RETURN_IF_ERROR(storage::CheckConninfo(o.from));
    StatusOr<storage::PgMapCatalog> catalog = storage::PgMapCatalog::Open(o.from);
    if (!catalog.ok()) return catalog.status();
    StatusOr<std::string> text = catalog->Settings(o.from_map);
    if (!text.ok()) return text.status();
    StatusOr<service::MapSettings> settings =
        service::ParseMapSettings(*text, "map '" + o.from_map + "' settings");
    if (!settings.ok()) return settings.status();
    src.settings = std::move(settings).value();
    // Its lease: no mapd serves the map while it is read.
    storage::PgOwnership own;
    own.instance = Importer();
    own.lease_ttl_s = kLeaseTtlS;
    StatusOr<std::unique_ptr<storage::PgStore>> store =
        storage::PgStore::Open(o.from, o.from_map, storage::StoreOptions{}, own);
    if (!store.ok()) {
      return Status(store.status().code(),
                    store.status().message() + " (stop the mapd instances serving it first)");
    }
    MAPD_RETURN_IF_ERROR(leases->Add(o.from, (*store)->lease()));
    src.store = std::move(store).value();
    return src;
  }
  std::error_code ec;
  if (!fs::is_regular_file(o.from, ec))
    return Status::NotFound("no database file '" + o.from + "'");
  MAPD_RETURN_IF_ERROR(service::CheckDatabaseFileModes(o.from));
  StatusOr<service::DatabaseLock> lock = service::DatabaseLock::Acquire(o.from);
  if (!lock.ok()) return lock.status();
  src.lock = std::move(lock).value();
  StatusOr<service::MapSettings> settings =
      service::ReadMapSettings(service::MapSettingsPath(o.from));
  if (!settings.ok()) return settings.status();
  src.settings = std::move(settings).value();
  StatusOr<std::unique_ptr<storage::SqliteStore>> store =
      storage::SqliteStore::Open(o.from, storage::StoreOptions{});
  if (!store.ok()) return store.status();
  src.store = std::move(store).value();
  return src;
}

unsigned long long U(uint64_t v) { return static_cast<unsigned long long>(v); }

void PrintReport(const storage::MapCopyReport& r, const std::string& where, double seconds) {
  std::printf("copied in %.1f s to %s:\n", seconds, where.c_str());
  std::printf("  %llu robots, %llu sessions, %llu observations (ids kept), %llu ties\n",
              U(r.robots), U(r.sessions), U(r.observations), U(r.ties));
  std::printf("  %llu fused walls, %llu fused planes\n", U(r.fused_lines), U(r.fused_planes));
  std::printf("  %llu submaps, %llu merges, %llu placements, global map: %s\n", U(r.submaps),
              U(r.merges), U(r.placements), r.global_map ? "yes" : "none");
  std::printf("  %llu audit rows, %llu tokens\n", U(r.audit_rows), U(r.tokens));
  for (const auto& [from, to] : r.submap_ids) {
    if (from != to)
      std::printf("  submap %lld is now %lld\n", static_cast<long long>(from),
                  static_cast<long long>(to));
  }
  for (const auto& [from, to] : r.merge_ids) {
    if (from != to)
      std::printf("  merge %lld is now %lld\n", static_cast<long long>(from),
                  static_cast<long long>(to));
  }
  std::printf(
      "snapshots are not copied: the first mapd to serve the map rebuilds its fusion state from "
      "the observations, then takes one\n");
}

// The copy's options: progress on stderr and the leases renewed every few
// seconds.
storage::MapCopyOptions CopyOptions(const MigrateOptions& o, Leases* leases) {
  storage::MapCopyOptions copy;
  copy.copy_tokens = o.with_tokens;
  copy.scope_tokens_to = o.map;
  auto last = std::make_shared<Clock::time_point>(Clock::now());
  copy.after_commit = [last, leases](const storage::MapCopyReport& r) {
    if (Clock::now() - *last < std::chrono::duration<double>(kRenewEveryS)) return Status::Ok();
    *last = Clock::now();
    std::fprintf(stderr, "mapd migrate: %llu observations, %llu submaps copied so far\n",
                 U(r.observations), U(r.submaps));
    return leases->Renew();
  };
  return copy;
}

// Into a PostgreSQL database: the map is made importing (unlisted, not
// served), filled, verified, then made ready; discarded if anything failed.
Status ToPostgres(const MigrateOptions& o, Source& src, Leases* leases) {
  MAPD_RETURN_IF_ERROR(storage::CheckConninfo(o.to));
  MAPD_RETURN_IF_ERROR(storage::CheckPgMapId(o.map));
  StatusOr<storage::PgMapCatalog> catalog = storage::PgMapCatalog::Open(o.to);
  if (!catalog.ok()) return catalog.status();
  const storage::PgInstance me = Importer();
  bool restarted = false;
  MAPD_RETURN_IF_ERROR(catalog->BeginImport(
      o.map, src.settings.empty() ? "" : service::MapSettingsText(src.settings), UnixNowNs(), me,
      kLeaseTtlS, &restarted));
  if (restarted) {
    std::fprintf(stderr,
                 "mapd migrate: an earlier migration into map '%s' did not finish; its part was "
                 "discarded and the copy starts again\n",
                 o.map.c_str());
  }
  const auto start = Clock::now();
  Status s = [&]() -> Status {
    storage::PgOwnership own;
    own.instance = me;
    own.lease_ttl_s = kLeaseTtlS;
    StatusOr<std::unique_ptr<storage::PgStore>> store =
        storage::PgStore::Open(o.to, o.map, storage::StoreOptions{}, own);
    if (!store.ok()) return store.status();
    MAPD_RETURN_IF_ERROR(leases->Add(o.to, (*store)->lease()));
    StatusOr<storage::MapCopyReport> report =
        storage::CopyMap(*src.store, **store, CopyOptions(o, leases));
    if (!report.ok()) return report.status();
    MAPD_RETURN_IF_ERROR(catalog->FinishImport((*store)->lease()));
    PrintReport(*report, "map '" + o.map + "' of the PostgreSQL database",
                std::chrono::duration<double>(Clock::now() - start).count());
    return Status::Ok();
  }();  // the store is closed here, its lease released: mapd takes the map
  if (!s.ok()) {
    if (Status d = catalog->DiscardImport(o.map); !d.ok()) {
      std::fprintf(stderr,
                   "mapd migrate: the partial copy could not be discarded (%s); it is never "
                   "served, and the next migration into '%s' discards it\n",
                   d.ToString().c_str(), o.map.c_str());
    }
  }
  return s;
}

void RemoveDatabaseFiles(const std::string& path) {
  std::error_code ec;
  for (const char* suffix : {"", "-wal", "-shm"}) fs::remove(path + suffix, ec);
}

// Into a SQLite file (DIR/<map>.db with --data-dir's layout, or a file of
// its own): written as <file>.migrating, then linked into place, which fails
// rather than replace a map that appeared meanwhile.
Status ToSqlite(const MigrateOptions& o, Source& src, Leases* leases) {
  std::error_code ec;
  std::string path, conf;
  if (fs::is_directory(o.to, ec)) {
    MAPD_RETURN_IF_ERROR(service::CheckMapId(o.map, "--map"));
    path = (fs::path(o.to) / (o.map + ".db")).string();
    conf = service::MapSettingsPath(path);
    if (o.with_tokens && o.map != service::kDefaultMapId) {
      return Status::InvalidArgument(
          "with --data-dir every map's tokens live in default.db: --with-tokens copies them only "
          "into the default map; make tokens for '" +
          o.map + "' with `mapd token create --db " + o.to + "/default.db --maps " + o.map + "`");
    }
  } else if (fs::path(o.to).extension() == ".db") {
    path = o.to;
    for (const auto& [key, value] : src.settings) {
      std::fprintf(stderr,
                   "mapd migrate: a single database file keeps no settings of its own; give mapd "
                   "--%s=%s\n",
                   key.c_str(), value.c_str());
    }
  } else {
    return Status::InvalidArgument(
        "--to '" + o.to +
        "' is none of: a PostgreSQL database (host=... or postgresql://...), a --data-dir "
        "directory, a new SQLite file ending in .db");
  }
  if (fs::exists(path, ec)) {
    return Status::AlreadyExists("'" + path +
                                 "' exists already; a migration makes a new map (choose another "
                                 "--map or file)");
  }
  if (!conf.empty() && fs::exists(conf, ec))
    return Status::AlreadyExists("'" + conf + "' exists already (settings of a removed map?)");

  const std::string part = path + ".migrating";
  if (fs::exists(part, ec)) {
    // A migration that died left it, or one is running now (it holds the lock).
    StatusOr<service::DatabaseLock> busy = service::DatabaseLock::Acquire(part);
    if (!busy.ok()) return Status::FailedPrecondition("another mapd migrate is writing " + part);
    RemoveDatabaseFiles(part);
  }
  const auto start = Clock::now();
  Status s = [&]() -> Status {
    // Locked before SQLite opens it: the lock's descriptor must outlive the
    // connections (map_directory.h).
    if (const int fd = ::open(part.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0600); fd >= 0)
      ::close(fd);
    StatusOr<service::DatabaseLock> lock = service::DatabaseLock::Acquire(part);
    if (!lock.ok()) return lock.status();
    StatusOr<std::unique_ptr<storage::SqliteStore>> store =
        storage::SqliteStore::Open(part, storage::StoreOptions{});
    if (!store.ok()) return store.status();
    StatusOr<storage::MapCopyReport> report =
        storage::CopyMap(*src.store, **store, CopyOptions(o, leases));
    if (!report.ok()) return report.status();
    MAPD_RETURN_IF_ERROR((*store)->Checkpoint());
    store->reset();  // closed: its WAL is folded in and removed
    if (!conf.empty() && !src.settings.empty())
      MAPD_RETURN_IF_ERROR(service::WriteMapSettings(conf, src.settings));
    if (::link(part.c_str(), path.c_str()) != 0) {
      const int err = errno;
      if (!conf.empty() && !src.settings.empty()) fs::remove(conf, ec);
      return Status::FailedPrecondition("cannot put the copy in place as '" + path +
                                        "': " + std::strerror(err));
    }
    PrintReport(*report, path, std::chrono::duration<double>(Clock::now() - start).count());
    return Status::Ok();
  }();
  RemoveDatabaseFiles(part);
  return s;
}

int Run(const MigrateOptions& o) {
  Leases leases;
  StatusOr<Source> src = OpenSource(o, &leases);
  if (!src.ok()) return MigrateFailed(src.status());
  const Status s = IsConninfo(o.to) ? ToPostgres(o, *src, &leases) : ToSqlite(o, *src, &leases);
  return s.ok() ? 0 : MigrateFailed(s);
}

}  // namespace

void AddMigrateCommand(CLI::App* app, std::function<int()>* action) {
  CLI::App* migrate = app->add_subcommand(
      "migrate", "move a map into another store, e.g. a SQLite file into PostgreSQL (offline)");
  migrate->footer(
      "Copies one map: observations with their ids, session ties, the fused map, submaps,\n"
      "merges, the global map and the audit log (docs/scale-out.md, \"Moving a map\").\n"
      "Robot, session, submap and merge ids are the target's own (printed old -> new).\n"
      "No mapd may serve the source meanwhile; the target map appears only when complete.\n"
      "  mapd migrate --from /var/lib/mapd/map.db --to 'host=db1 dbname=mapd' --map site-1\n"
      "  mapd migrate --from 'host=db1 dbname=mapd' --from-map site-1 --to /var/lib/mapd/maps "
      "--map site-1");
  auto o = std::make_shared<MigrateOptions>();
  migrate
      ->add_option("--from", o->from,
                   "the source: a SQLite database file, or a PostgreSQL database (host=... or "
                   "postgresql://...; the password from PGPASSWORD or ~/.pgpass)")
      ->required();
  migrate->add_option("--from-map", o->from_map,
                      "the map to copy, when --from is PostgreSQL (default: default)");
  migrate
      ->add_option("--to", o->to,
                   "the target: a PostgreSQL database, a --data-dir directory, or a new .db file")
      ->required();
  migrate->add_option("--map", o->map, "the new map's id in the target (not for a .db file)");
  migrate->add_flag("--with-tokens", o->with_tokens,
                    "copy the source's tokens too; those that act on every map are scoped to "
                    "--map (PostgreSQL keeps tokens for the whole database)");
  migrate->callback([o, action] {
    *action = [o] {
      if (o->map.empty() && fs::path(o->to).extension() != ".db") {
        std::fprintf(stderr, "mapd migrate: give --map ID, the map's id in the target\n");
        return 2;
      }
      return Run(*o);
    };
  });
}

}  // namespace mapd
