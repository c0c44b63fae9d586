// What outlives one call in a map's life: making, archiving, deleting and
// restoring maps. MapServer does it (it owns the maps, their health and, on
// PostgreSQL, the catalog); MapRouter checks the caller, asks, and audits.
#ifndef MAPD_SERVICE_MAP_LIFECYCLE_H_
#define MAPD_SERVICE_MAP_LIFECYCLE_H_

#include <string>
#include <vector>

#include "common/status.h"
#include "service/map_archive.h"
#include "service/map_directory.h"

namespace mapd::service {

class MapLifecycle {
 public:
  virtual ~MapLifecycle() = default;

  // A map CreateMap made, now in the directory: its health and logs.
  virtual void Created(ServedMap* map) = 0;
  // Stops serving map `id` (streams drained, what is queued committed) and
  // archives it, or with `purge` deletes its data for good; an archived
  // map is purged too. Returns where the archive is ("" when purged).
  // FailedPrecondition for the default map and with one database (--db);
  // NotFound when the map is neither served here nor archived.
  virtual StatusOr<std::string> DeleteMap(const std::string& id, bool purge) = 0;
  // Serves archived map `id` again. Null (and Ok) when another instance of
  // a shared database took it first. NotFound when it is not archived.
  virtual StatusOr<MapHold> RestoreMap(const std::string& id) = 0;
  virtual StatusOr<std::vector<ArchivedMap>> ListArchived() = 0;
};

}  // namespace mapd::service

#endif  // MAPD_SERVICE_MAP_LIFECYCLE_H_
