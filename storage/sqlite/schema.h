// The database schema and its migrations.
#ifndef MAPD_STORAGE_SQLITE_SCHEMA_H_
#define MAPD_STORAGE_SQLITE_SCHEMA_H_

#include <sqlite3.h>

#include <cstdint>
#include <string>

#include "common/status.h"

namespace mapd::storage {

// The schema version this build writes.
int CurrentSchemaVersion();

// PRAGMA application_id of a mapd database ("mapd" in ASCII), so that mapd
// never adopts another application's SQLite file, and `file` names it.
constexpr int32_t kApplicationId = 0x6d617064;

// Claims the database for mapd, or refuses it. Empty: stamped with
// kApplicationId. Stamped by mapd: accepted. Written by an earlier mapd
// (before the stamp, recognised by its schema_version and observations
// tables): stamped and accepted. Anything else (another application_id, or
// tables of another application): FailedPrecondition naming what was found.
// A new database gets auto_vacuum=INCREMENTAL before its first page.
// It writes the database header each time, so a read-only database (file,
// directory or mount) is refused here too, with the reason. `path` is for
// the messages.
Status ClaimDatabase(sqlite3* db, const std::string& path);

// Brings the database up to CurrentSchemaVersion(), one migration per
// transaction. A database written by a NEWER mapd is refused (FailedPrecondition)
// rather than opened and damaged.
Status Migrate(sqlite3* db);

}  // namespace mapd::storage

#endif  // MAPD_STORAGE_SQLITE_SCHEMA_H_
