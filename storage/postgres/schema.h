// The PostgreSQL schema: one database holds many maps, every table keyed by
// map id first. Observations are partitioned by map (one partition per map,
// made when the map is first opened), so that one map's rows are one table
// to scan, vacuum, move or drop.
#ifndef MAPD_STORAGE_POSTGRES_SCHEMA_H_
#define MAPD_STORAGE_POSTGRES_SCHEMA_H_

#include <string>

#include "common/status.h"
#include "storage/postgres/pq.h"

namespace mapd::storage {

// The schema version this build writes.
int CurrentPostgresSchemaVersion();

// Brings the database up to CurrentPostgresSchemaVersion(), all in one
// transaction under an advisory lock, so several mapd starting together
// against an empty database migrate it once and the others wait and see it
// done. A database written by a newer mapd is refused (FailedPrecondition).
Status MigratePostgres(PgConnection& conn);

// A map's row in `maps` and its observation partition.
struct MapRow {
  int64_t num = 0;        // names the partition
  std::string partition;  // its observations' table, "observations_<num>"
};
// Adds `map_id`'s row and partition if missing (CheckPgMapId first).
StatusOr<MapRow> EnsureMap(PgConnection& conn, const std::string& map_id, int64_t now_ns);
// Deletes every row of `map_id`, its partition and its catalog row, in one
// transaction. Ok if there is no such map, unless `only_archived`: then
// NotFound, and FailedPrecondition for a map that is not archived (checked
// under the map row's lock, so that a restore and a purge do not interleave).
Status DeleteMapRows(PgConnection& conn, const std::string& map_id, bool only_archived = false);

}  // namespace mapd::storage

#endif  // MAPD_STORAGE_POSTGRES_SCHEMA_H_
