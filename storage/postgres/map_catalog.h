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

  // Every map's id, sorted.
  StatusOr<std::vector<std::string>> ListMaps();
  // Adds map `id` with `settings` (opaque text); AlreadyExists if it exists,
  // InvalidArgument for a malformed id. With `owner`, in the same statement a
  // lease for it (epoch 0, ttl_s): the instance that makes a map serves it
  // (its PgStore::Open takes epoch 1), another does not take it first.
  Status CreateMap(const std::string& id, const std::string& settings, int64_t now_ns,
                   const PgInstance* owner = nullptr, double ttl_s = 0);
  // A map's settings ('' when it has none); NotFound when there is no such map.
  StatusOr<std::string> Settings(const std::string& id);

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
