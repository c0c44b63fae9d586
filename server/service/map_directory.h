// The maps one mapd serves (docs/scale-out.md). A map is one map frame: its
// own database file, MapCore (fusion engines, writer and fuser threads) and
// MapServiceImpl (handlers, uploads, merges). With --db there is one map,
// "default"; with --data-dir every <id>.db file of the directory is a map,
// "default" is made when missing, and Create() adds maps while serving.
// With a PostgreSQL store the directory holds the maps this instance owns
// (map_ownership.h opens them, Serve, and drops them, Retire).
//
// Each database file is locked (flock, exclusive) while it is served, so a
// second mapd on the same file refuses to start instead of writing beside
// the first.
//
// A call holds the map it works on (MapHold) until it ends. A map taken out
// of the directory (Retire: DeleteMap, a handoff, a lost lease) stays
// allocated, stopped, while anything holds it; Reap frees it after that.
//
// Thread safety: every method may be called from any thread.
#ifndef MAPD_SERVICE_MAP_DIRECTORY_H_
#define MAPD_SERVICE_MAP_DIRECTORY_H_

#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "common/status.h"
#include "service/map_core.h"
#include "service/map_id.h"
#include "service/map_service.h"
#include "service/map_settings.h"

namespace mapd::service {

// An exclusive flock on a database file, held until destroyed. flock locks
// are apart from the fcntl locks SQLite takes, so they do not interfere; the
// descriptor must outlive the database's connections (closing any descriptor
// of a file drops the process's fcntl locks on it), hence ServedMap's order.
class DatabaseLock {
 public:
  // FailedPrecondition naming the file when another process holds it.
  static StatusOr<DatabaseLock> Acquire(const std::string& path);
  DatabaseLock() = default;
  DatabaseLock(DatabaseLock&& other) noexcept;
  DatabaseLock& operator=(DatabaseLock&& other) noexcept;
  ~DatabaseLock();

 private:
  int fd_ = -1;
};

struct ServedMap {
  std::string id;
  std::string db_path;
  // Members are destroyed bottom up: the service, then the core (which
  // closes the database), then the lock.
  DatabaseLock lock;
  MapSettings settings;  // its own, over the server's (map_settings.h)
  std::unique_ptr<MapCore> core;
  std::unique_ptr<MapServiceImpl> service;
};

// A served map, held: it is not freed while a hold lives (Reap).
using MapHold = std::shared_ptr<ServedMap>;

// What belongs to the server rather than a map (tokens, WhoAmI, the denial
// counts): the default map's core and service, or on PostgreSQL its own
// (server_wide_core.h), since the default map may be served elsewhere.
struct ServerWide {
  std::unique_ptr<Core> core;
  std::unique_ptr<MapServiceImpl> service;
};

class MapDirectory {
 public:
  // Opens map `id` at `db_path` (locked by the caller's ServedMap) and its
  // service; `shared_with` is the default map's service (null for the
  // default map itself). `create_with`: a new map's own settings, to check
  // and store first; null when opening a map that exists.
  using Opener = std::function<StatusOr<std::unique_ptr<ServedMap>>(
      const std::string& id, const std::string& db_path, MapServiceImpl* shared_with,
      const MapSettings* create_with)>;

  // One map, "default", in the file `db_path`.
  static StatusOr<std::unique_ptr<MapDirectory>> OpenSingle(const std::string& db_path,
                                                            Opener opener);
  // Every <id>.db of `data_dir`, which must exist: "default" first (made
  // when missing), then the others by id.
  static StatusOr<std::unique_ptr<MapDirectory>> OpenDataDir(const std::string& data_dir,
                                                             Opener opener);
  // For the maps of a PostgreSQL database, none open yet (Serve). The
  // opener gets an empty db_path, and a new map's settings to store with it;
  // every map's service shares `server_wide`'s.
  static std::unique_ptr<MapDirectory> ForPostgres(ServerWide server_wide, Opener opener);

  // The other maps first: their services share the default map's access
  // control and stream limiter.
  ~MapDirectory();

  // NotFound naming the id (never the other maps: the caller may not be
  // authenticated yet).
  StatusOr<MapHold> Find(const std::string& id) const;
  // The server's parts (ServerWide): the default map's, or ForPostgres's.
  MapServiceImpl& server_wide() const;
  Core& server_wide_core() const;
  // The default map when served here, else null.
  ServedMap* default_map() const;
  std::vector<MapHold> List() const;     // by id
  std::vector<std::string> Ids() const;  // sorted
  // The map's core, held (as Find), or null when not served.
  std::shared_ptr<Core> FindCore(const std::string& id) const;
  // A new, empty map with its own `settings`. FailedPrecondition with one
  // database (--db), AlreadyExists, InvalidArgument for a bad id or setting,
  // or the opener's error.
  StatusOr<MapHold> Create(const std::string& id, const MapSettings& settings = {});
  bool can_create() const { return !data_dir_.empty() || postgres_; }
  // PostgreSQL: opens existing map `id` here (the opener takes its lease).
  StatusOr<MapHold> Serve(const std::string& id);
  // --data-dir: opens map `id` from its file, which is back in the
  // directory (map_archive.h); AlreadyExists when it is served.
  StatusOr<MapHold> Reopen(const std::string& id);
  // Takes map `id` out of the directory (calls for it then find it gone)
  // and returns it for the caller to stop. It stays allocated while calls
  // hold it. Null when it is not served.
  MapHold Retire(const std::string& id);
  // Frees the retired maps no call holds any more (their connections,
  // file locks and memory); returns how many retired maps are still held.
  size_t Reap();
  bool postgres() const { return postgres_; }
  const std::string& data_dir() const { return data_dir_; }

 private:
  MapDirectory(std::string data_dir, Opener opener)
      : data_dir_(std::move(data_dir)), opener_(std::move(opener)) {}
  StatusOr<MapHold> Open(const std::string& id, const std::string& db_path,
                         const MapSettings* create_with = nullptr);

  const std::string data_dir_;  // empty: one database, or PostgreSQL
  bool postgres_ = false;       // maps of a PostgreSQL database
  const Opener opener_;
  std::mutex create_mu_;  // one Create at a time (it opens files)
  mutable std::mutex mu_;
  std::map<std::string, MapHold> maps_;  // GUARDED_BY(mu_)
  std::vector<MapHold> retired_;         // GUARDED_BY(mu_)
  ServedMap* default_ = nullptr;         // GUARDED_BY(mu_); with a local store set once, first
  ServerWide server_wide_;               // PostgreSQL only; destroyed after every map
};

}  // namespace mapd::service

#endif  // MAPD_SERVICE_MAP_DIRECTORY_H_
