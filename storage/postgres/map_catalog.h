// The maps a PostgreSQL database holds (table `maps`), for mapd's map
// directory: which maps exist, and each one's own settings. Opening a map's
// store (PgStore::Open) adds its row if missing; CreateMap adds one with
// settings first.
#ifndef MAPD_STORAGE_POSTGRES_MAP_CATALOG_H_
#define MAPD_STORAGE_POSTGRES_MAP_CATALOG_H_

#include <cstdint>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "common/status.h"
#include "storage/postgres/map_lease.h"
#include "storage/postgres/pq.h"

namespace mapd::storage {

// Thread safety: every method may be called from any thread (one
// connection, under a mutex; connected again once if it broke).
class PgMapCatalog {
 public:
  // Connects and migrates the schema (schema.h).
  static StatusOr<PgMapCatalog> Open(const std::string& conninfo);

  // Every map's id, sorted (not the archived or importing ones).
  StatusOr<std::vector<std::string>> ListMaps();
  // Adds map `id` with `settings` (opaque text); AlreadyExists if it exists,
  // InvalidArgument for a malformed id. With `owner`, in the same statement a
  // lease for it (epoch 0, ttl_s): the instance that makes a map serves it
  // (its PgStore::Open takes epoch 1), another does not take it first.
  Status CreateMap(const std::string& id, const std::string& settings, int64_t now_ns,
                   const PgInstance* owner = nullptr, double ttl_s = 0);
  // A map's settings ('' when it has none); NotFound when there is no such
  // map (or it is being imported, or archived).
  StatusOr<std::string> Settings(const std::string& id);

  // --- Imports (mapd migrate): a map copied in from elsewhere is in the
  // catalog, so that its rows have an owner, but neither listed nor served
  // until FinishImport.
  // Adds map `id` as importing with `settings`, and a lease for `importer`
  // (who then opens it: PgStore::Open with that instance). AlreadyExists if
  // the map exists; FailedPrecondition naming the holder while another
  // import of it is alive. An import whose lease lapsed (its copier died)
  // is discarded first, and *restarted is set.
  Status BeginImport(const std::string& id, const std::string& settings, int64_t now_ns,
                     const PgInstance& importer, double ttl_s, bool* restarted);
  // The import is complete: mapd lists and serves the map from now on.
  // FailedPrecondition unless `lease` (the importer's, PgStore::lease()) is
  // still the map's: a copier paused past its lease cannot publish the map
  // another import is filling.
  Status FinishImport(const MapLease& lease);
  // Deletes an importing map and every row of it (a copy that failed).
  // FailedPrecondition for a map that is not importing.
  Status DiscardImport(const std::string& id);

  // --- Archives (DeleteMap without purge): the map's rows stay, and no
  // instance lists or serves it until RestoreMap.
  struct Archived {
    std::string id;
    int64_t archived_ns = 0;
  };
  // Archives the map of `lease` (its owner's, whose writer has stopped):
  // the lease passes to nobody, for ever, with the next epoch, so that a
  // write of the old owner's can no longer commit. FailedPrecondition when
  // `lease` is no longer the map's.
  Status ArchiveMap(const MapLease& lease, int64_t now_ns);
  // The archived maps, by id.
  StatusOr<std::vector<Archived>> ListArchived();
  // Lists and serves map `id` again (its lease lapsed: any instance takes
  // it). NotFound / FailedPrecondition when it is not there / not archived.
  Status RestoreMap(const std::string& id);
  // Deletes an archived map and every row of it, for good (NotFound /
  // FailedPrecondition as RestoreMap).
  Status PurgeArchived(const std::string& id);

 private:
  StatusOr<PgResult> Query(const std::string& sql, const PgParams& params);

  std::string conninfo_;
  std::unique_ptr<std::mutex> mu_ = std::make_unique<std::mutex>();  // guards conn_
  PgConnection conn_;
};

// Map ids on PostgreSQL are mapd's map ids: 1-128 of A-Z a-z 0-9 _ . -, not
// starting with '.' (InvalidArgument otherwise).
Status CheckPgMapId(const std::string& id);

}  // namespace mapd::storage

#endif  // MAPD_STORAGE_POSTGRES_MAP_CATALOG_H_
