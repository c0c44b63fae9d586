// Archived maps of a --data-dir (DeleteMap without purge): a map's files
// move from DIR into DIR/archive/, where no mapd serves them (a start
// serves DIR's own <id>.db files only) and RestoreMap finds them again.
// The files are the map, unchanged: an archive can also be copied away and
// served elsewhere (mapd --db DIR/archive/<id>.db, or mapd migrate).
//
// The caller serialises calls for one directory; each function is one set
// of renames (or unlinks) that never replaces a file.
#ifndef MAPD_SERVICE_MAP_ARCHIVE_H_
#define MAPD_SERVICE_MAP_ARCHIVE_H_

#include <cstdint>
#include <string>
#include <vector>

#include "common/status.h"

namespace mapd::service {

struct ArchivedMap {
  std::string id;
  int64_t archived_ns = 0;  // when it was archived (Unix time, ns)
};

// DIR/archive/<id>.db.
std::string ArchivedMapPath(const std::string& data_dir, const std::string& id);
bool IsArchived(const std::string& data_dir, const std::string& id);

// Moves <id>.db, its -wal and -shm files and <id>.conf from `data_dir` into
// its archive (made if missing). AlreadyExists when an archive of `id` is
// there; the map must not be served (its writer stopped).
Status ArchiveMapFiles(const std::string& data_dir, const std::string& id);
// The reverse: NotFound when there is no archive of `id`, AlreadyExists
// when `data_dir` has a file of that name.
Status RestoreMapFiles(const std::string& data_dir, const std::string& id);
// Deletes the archive of `id` for good; NotFound when there is none.
Status PurgeArchivedFiles(const std::string& data_dir, const std::string& id);
// Every archived map, by id.
StatusOr<std::vector<ArchivedMap>> ListArchivedFiles(const std::string& data_dir);

}  // namespace mapd::service

#endif  // MAPD_SERVICE_MAP_ARCHIVE_H_
