// The database schema and its migrations.
#ifndef MAPD_STORAGE_SCHEMA_H_
#define MAPD_STORAGE_SCHEMA_H_

#include <sqlite3.h>

#include "common/status.h"

namespace mapd::storage {

// The schema version this build writes.
int CurrentSchemaVersion();

// Brings the database up to CurrentSchemaVersion(), one migration per
// transaction. A database written by a NEWER mapd is refused (FailedPrecondition)
// rather than opened and damaged.
Status Migrate(sqlite3* db);

}  // namespace mapd::storage

#endif  // MAPD_STORAGE_SCHEMA_H_
