// The modes of the files that hold mapd's secrets.
//
// The database holds the token hashes (anyone who can write it can add an
// admin token offline) and every map; the TLS key is the server's identity.
// mapd creates files owner-only (main() sets umask 077; SQLite gives the
// -wal and -shm files the database's mode), and at start it checks files
// that already exist:
//   - writable by group or others: refused (FailedPrecondition), naming the
//     file, its mode and the fix (chmod);
//   - readable by group or others: a warning (event=file_readable_by_others):
//     deployments may share a key with a group on purpose (Debian's ssl-cert);
//   - the database's directory writable by others without the sticky bit:
//     refused (anyone could replace the database).
#ifndef MAPD_SERVICE_FILE_MODES_H_
#define MAPD_SERVICE_FILE_MODES_H_

#include <string>

#include "common/status.h"

namespace mapd::service {

// Checks `db` and its -wal and -shm files, and its directory (the files may
// not exist yet: that is fine).
Status CheckDatabaseFileModes(const std::string& db);

// Checks a secret that must exist, e.g. `what` = "tls_key".
Status CheckSecretFileMode(const std::string& path, const std::string& what);

}  // namespace mapd::service

#endif  // MAPD_SERVICE_FILE_MODES_H_
