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

// Makes `map_id`'s partitions if missing. `map_id` must be a map id
// ([A-Za-z0-9_.-], 1-64 characters): InvalidArgument otherwise.
Status EnsureMapPartitions(PgConnection& conn, const std::string& map_id);

}  // namespace mapd::storage

#endif  // MAPD_STORAGE_POSTGRES_SCHEMA_H_
