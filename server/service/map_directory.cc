#include "service/map_directory.h"

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <iterator>

#include "service/file_modes.h"
#include "service/map_archive.h"

namespace mapd::service {
namespace {

constexpr char kDbSuffix[] = ".db";

std::string PathOf(const std::string& dir, const std::string& id) {
  return (std::filesystem::path(dir) / (id + kDbSuffix)).string();
}

}  // namespace

StatusOr<DatabaseLock> DatabaseLock::Acquire(const std::string& path) {
  // Read-only is enough for flock, and leaves a read-only database to the
  // store's clearer refusal. Created owner-only if missing: SQLite takes an
  // empty file as a new database.
  int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0 && errno == ENOENT) fd = ::open(path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0600);
  if (fd < 0) {
    return Status::FailedPrecondition("cannot open the database '" + path +
                                      "': " + std::strerror(errno));
  }
  if (::flock(fd, LOCK_EX | LOCK_NB) != 0) {
    const int err = errno;
    ::close(fd);
    if (err == EWOULDBLOCK) {
      return Status::FailedPrecondition(
          "the database '" + path +
          "' is in use by another mapd (it holds the file's lock); one mapd serves a database "
          "at a time: stop the other, or give this one another --db or --data-dir");
    }
    return Status::FailedPrecondition("cannot lock the database '" + path +
                                      "': " + std::strerror(err));
  }
  DatabaseLock lock;
  lock.fd_ = fd;
  return lock;
}

DatabaseLock::DatabaseLock(DatabaseLock&& other) noexcept : fd_(other.fd_) { other.fd_ = -1; }

DatabaseLock& DatabaseLock::operator=(DatabaseLock&& other) noexcept {
  if (this != &other) {
    if (fd_ >= 0) ::close(fd_);
    fd_ = other.fd_;
    other.fd_ = -1;
  }
  return *this;
}

DatabaseLock::~DatabaseLock() {
  if (fd_ >= 0) ::close(fd_);  // closing the descriptor releases the flock
}

StatusOr<std::unique_ptr<MapDirectory>> MapDirectory::OpenSingle(const std::string& db_path,
                                                                 Opener opener) {
  std::unique_ptr<MapDirectory> d(new MapDirectory("", std::move(opener)));
  StatusOr<MapHold> map = d->Open(kDefaultMapId, db_path);
  if (!map.ok()) return map.status();
  return d;
}

StatusOr<std::unique_ptr<MapDirectory>> MapDirectory::OpenDataDir(const std::string& data_dir,
                                                                  Opener opener) {
  std::error_code ec;
  if (!std::filesystem::is_directory(data_dir, ec)) {
    return Status::FailedPrecondition("--data-dir '" + data_dir +
                                      "' is not a directory; create it first (mkdir -p)");
  }
  std::vector<std::string> ids;
  for (const auto& entry : std::filesystem::directory_iterator(data_dir, ec)) {
    const std::filesystem::path& p = entry.path();
    if (!entry.is_regular_file() || p.extension() != kDbSuffix) continue;
    const std::string id = p.stem().string();
    if (id == kDefaultMapId) continue;
    // Another .db beside the maps is not one: say so rather than serve it.
    if (Status s = CheckMapId(id, "the file " + p.string() + ": its name"); !s.ok()) return s;
    ids.push_back(id);
  }
  if (ec)
    return Status::FailedPrecondition("cannot list --data-dir '" + data_dir + "': " + ec.message());
  std::sort(ids.begin(), ids.end());
  std::unique_ptr<MapDirectory> d(new MapDirectory(data_dir, std::move(opener)));
  StatusOr<MapHold> map = d->Open(kDefaultMapId, PathOf(data_dir, kDefaultMapId));
  if (!map.ok()) return map.status();
  for (const std::string& id : ids) {
    map = d->Open(id, PathOf(data_dir, id));
    if (!map.ok()) return map.status();
  }
  return d;
}

std::unique_ptr<MapDirectory> MapDirectory::ForPostgres(ServerWide server_wide, Opener opener) {
  std::unique_ptr<MapDirectory> d(new MapDirectory("", std::move(opener)));
  d->postgres_ = true;
  d->server_wide_ = std::move(server_wide);
  return d;
}

StatusOr<MapHold> MapDirectory::Serve(const std::string& id) {
  std::lock_guard<std::mutex> opening(create_mu_);
  if (Find(id).ok()) return Status::AlreadyExists("map '" + id + "' is served here already");
  return Open(id, "");
}

StatusOr<MapHold> MapDirectory::Reopen(const std::string& id) {
  MAPD_RETURN_IF_ERROR(CheckMapId(id, "map_id"));
  if (data_dir_.empty()) {
    return Status::FailedPrecondition("only a --data-dir mapd opens a map from its file");
  }
  std::lock_guard<std::mutex> opening(create_mu_);
  if (Find(id).ok()) return Status::AlreadyExists("map '" + id + "' is served here already");
  return Open(id, PathOf(data_dir_, id));
}

MapHold MapDirectory::Retire(const std::string& id) {
  std::lock_guard<std::mutex> lock(mu_);
  auto it = maps_.find(id);
  if (it == maps_.end()) return nullptr;
  MapHold map = it->second;
  retired_.push_back(std::move(it->second));
  maps_.erase(it);
  if (default_ == map.get()) default_ = nullptr;
  return map;
}

size_t MapDirectory::Reap() {
  std::vector<MapHold> unheld;  // freed after the lock: a map's stop may take a while
  size_t held = 0;
  {
    std::lock_guard<std::mutex> lock(mu_);
    // use_count() is exact here: a retired map is reachable from retired_
    // and from holds made before it was retired, and no new hold is made.
    auto keep = std::partition(retired_.begin(), retired_.end(),
                               [](const MapHold& m) { return m.use_count() > 1; });
    held = static_cast<size_t>(keep - retired_.begin());
    std::move(keep, retired_.end(), std::back_inserter(unheld));
    retired_.erase(keep, retired_.end());
  }
  return held;
}

MapServiceImpl& MapDirectory::server_wide() const {
  if (server_wide_.service) return *server_wide_.service;
  std::lock_guard<std::mutex> lock(mu_);
  return *default_->service;  // a local store's default map is never retired
}

Core& MapDirectory::server_wide_core() const {
  if (server_wide_.core) return *server_wide_.core;
  std::lock_guard<std::mutex> lock(mu_);
  return *default_->core;
}

ServedMap* MapDirectory::default_map() const {
  std::lock_guard<std::mutex> lock(mu_);
  return default_;
}

StatusOr<MapHold> MapDirectory::Open(const std::string& id, const std::string& db_path,
                                     const MapSettings* create_with) {
  if (!postgres_) MAPD_RETURN_IF_ERROR(CheckDatabaseFileModes(db_path));
  MapServiceImpl* shared_with = server_wide_.service.get();
  if (shared_with == nullptr) {
    std::lock_guard<std::mutex> lock(mu_);
    shared_with = default_ == nullptr ? nullptr : default_->service.get();
  }
  StatusOr<std::unique_ptr<ServedMap>> map = opener_(id, db_path, shared_with, create_with);
  if (!map.ok()) return map.status();
  MapHold held(std::move(map).value());
  std::lock_guard<std::mutex> lock(mu_);
  maps_.emplace(id, held);
  if (id == kDefaultMapId) default_ = held.get();
  return held;
}

MapDirectory::~MapDirectory() {
  // With a local store the other maps' services share the default map's:
  // they go first. The server-wide parts go last (a member).
  MapHold default_map;
  if (auto it = maps_.find(kDefaultMapId); it != maps_.end()) default_map = std::move(it->second);
  maps_.clear();
  retired_.clear();
  default_map.reset();
}

StatusOr<MapHold> MapDirectory::Find(const std::string& id) const {
  std::lock_guard<std::mutex> lock(mu_);
  auto it = maps_.find(id.empty() ? std::string(kDefaultMapId) : id);
  if (it == maps_.end()) {
    return Status::NotFound("map '" + id.substr(0, 128) +
                            "' is not served here; ListMaps (mapctl maps) names the maps");
  }
  return it->second;
}

std::vector<MapHold> MapDirectory::List() const {
  std::lock_guard<std::mutex> lock(mu_);
  std::vector<MapHold> out;
  for (const auto& [id, map] : maps_) out.push_back(map);
  return out;
}

std::vector<std::string> MapDirectory::Ids() const {
  std::lock_guard<std::mutex> lock(mu_);
  std::vector<std::string> out;
  for (const auto& [id, map] : maps_) out.push_back(id);
  return out;
}

std::shared_ptr<Core> MapDirectory::FindCore(const std::string& id) const {
  StatusOr<MapHold> map = Find(id);
  if (!map.ok()) return nullptr;
  Core* core = (*map)->core.get();
  return std::shared_ptr<Core>(*std::move(map), core);  // holds the map
}

StatusOr<MapHold> MapDirectory::Create(const std::string& id, const MapSettings& settings) {
  MAPD_RETURN_IF_ERROR(CheckMapId(id, "map_id"));
  if (!can_create()) {
    return Status::FailedPrecondition(
        "this mapd serves one database (--db); start it with --data-dir DIR to serve several "
        "maps and create more");
  }
  std::lock_guard<std::mutex> creating(create_mu_);
  if (Find(id).ok()) return Status::AlreadyExists("map '" + id + "' exists already");
  if (postgres_) return Open(id, "", &settings);  // the opener adds the map's row
  if (IsArchived(data_dir_, id)) {
    return Status::AlreadyExists("map '" + id + "' is archived (" + ArchivedMapPath(data_dir_, id) +
                                 "): restore it (mapctl maps restore " + id +
                                 ") or delete it for good (mapctl maps delete " + id +
                                 " --purge) first");
  }
  const std::string path = PathOf(data_dir_, id);
  std::error_code ec;
  if (std::filesystem::exists(path, ec)) {
    // Not served, yet there: another mapd made it, or a file was copied in.
    return Status::AlreadyExists("the file '" + path +
                                 "' exists but is not served here; restart mapd to serve it");
  }
  return Open(id, path, &settings);
}

}  // namespace mapd::service
