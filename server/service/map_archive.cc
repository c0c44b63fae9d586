#include "service/map_archive.h"

#include <fcntl.h>
#include <stdio.h>  // renameat2, RENAME_NOREPLACE
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <filesystem>

#include "service/map_id.h"

namespace mapd::service {
namespace {

namespace fs = std::filesystem;

constexpr char kArchiveDir[] = "archive";

// A map's files, the database first: its move is what takes the map out of
// (or puts it back into) the directory mapd serves.
std::vector<std::string> MapFiles(const std::string& id) {
  return {id + ".db", id + ".db-wal", id + ".db-shm", id + ".conf"};
}

std::string ArchiveDir(const std::string& data_dir) {
  return (fs::path(data_dir) / kArchiveDir).string();
}

bool Exists(const std::string& path) {
  struct stat st;
  return ::lstat(path.c_str(), &st) == 0;
}

// The first of map `id`'s files that is in `dir`; "" when none is.
std::string FirstThere(const std::string& dir, const std::string& id) {
  for (const std::string& f : MapFiles(id)) {
    std::string path = (fs::path(dir) / f).string();
    if (Exists(path)) return path;
  }
  return "";
}

// Renames `from` to `to` unless `to` exists; a missing `from` is fine.
Status MoveIfThere(const std::string& from, const std::string& to) {
  if (::renameat2(AT_FDCWD, from.c_str(), AT_FDCWD, to.c_str(), RENAME_NOREPLACE) == 0 ||
      errno == ENOENT) {
    return Status::Ok();
  }
  const int err = errno;
  if (err == EEXIST) return Status::AlreadyExists("'" + to + "' exists already");
  return Status::Internal("cannot move '" + from + "' to '" + to + "': " + std::strerror(err));
}

Status Move(const std::string& from_dir, const std::string& to_dir, const std::string& id,
            bool database_first) {
  std::vector<std::string> files = MapFiles(id);
  if (!database_first) std::reverse(files.begin(), files.end());
  for (const std::string& f : files) {
    MAPD_RETURN_IF_ERROR(
        MoveIfThere((fs::path(from_dir) / f).string(), (fs::path(to_dir) / f).string()));
  }
  return Status::Ok();
}

}  // namespace

std::string ArchivedMapPath(const std::string& data_dir, const std::string& id) {
  return (fs::path(ArchiveDir(data_dir)) / (id + ".db")).string();
}

bool IsArchived(const std::string& data_dir, const std::string& id) {
  return Exists(ArchivedMapPath(data_dir, id));
}

Status ArchiveMapFiles(const std::string& data_dir, const std::string& id) {
  MAPD_RETURN_IF_ERROR(CheckMapId(id, "map_id"));
  const std::string archive = ArchiveDir(data_dir);
  if (::mkdir(archive.c_str(), 0700) != 0 && errno != EEXIST) {
    return Status::Internal("cannot make the archive directory '" + archive +
                            "': " + std::strerror(errno));
  }
  if (const std::string there = FirstThere(archive, id); !there.empty()) {
    return Status::AlreadyExists("'" + there + "' exists already (an earlier archive of map '" +
                                 id + "'); move it away first");
  }
  MAPD_RETURN_IF_ERROR(Move(data_dir, archive, id, /*database_first=*/true));
  // Its modification time says when it was archived (ListArchivedFiles).
  ::utimensat(AT_FDCWD, ArchivedMapPath(data_dir, id).c_str(), nullptr, 0);
  return Status::Ok();
}

Status RestoreMapFiles(const std::string& data_dir, const std::string& id) {
  MAPD_RETURN_IF_ERROR(CheckMapId(id, "map_id"));
  if (!IsArchived(data_dir, id)) {
    return Status::NotFound("map '" + id + "' is not archived (no " +
                            ArchivedMapPath(data_dir, id) + ")");
  }
  if (const std::string here = FirstThere(data_dir, id); !here.empty()) {
    return Status::AlreadyExists("'" + here + "' exists; move it away to restore map '" + id + "'");
  }
  // The database last: until it is back, the map is not in the directory.
  return Move(ArchiveDir(data_dir), data_dir, id, /*database_first=*/false);
}

Status PurgeArchivedFiles(const std::string& data_dir, const std::string& id) {
  MAPD_RETURN_IF_ERROR(CheckMapId(id, "map_id"));
  if (!IsArchived(data_dir, id)) {
    return Status::NotFound("map '" + id + "' is not archived (no " +
                            ArchivedMapPath(data_dir, id) + ")");
  }
  for (const std::string& f : MapFiles(id)) {
    const std::string path = (fs::path(ArchiveDir(data_dir)) / f).string();
    if (::unlink(path.c_str()) != 0 && errno != ENOENT) {
      return Status::Internal("cannot delete '" + path + "': " + std::strerror(errno));
    }
  }
  return Status::Ok();
}

StatusOr<std::vector<ArchivedMap>> ListArchivedFiles(const std::string& data_dir) {
  std::vector<ArchivedMap> out;
  std::error_code ec;
  const std::string archive = ArchiveDir(data_dir);
  if (!fs::is_directory(archive, ec)) return out;
  for (const auto& entry : fs::directory_iterator(archive, ec)) {
    const fs::path& p = entry.path();
    if (!entry.is_regular_file() || p.extension() != ".db") continue;
    const std::string id = p.stem().string();
    if (!CheckMapId(id, "").ok()) continue;  // not an archived map
    struct stat st;
    if (::stat(p.c_str(), &st) != 0) continue;
    out.push_back({id, static_cast<int64_t>(st.st_mtim.tv_sec) * 1000000000 + st.st_mtim.tv_nsec});
  }
  if (ec) return Status::Internal("cannot list '" + archive + "': " + ec.message());
  std::sort(out.begin(), out.end(),
            [](const ArchivedMap& a, const ArchivedMap& b) { return a.id < b.id; });
  return out;
}

}  // namespace mapd::service
