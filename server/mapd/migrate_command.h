// `mapd migrate --from SOURCE --to TARGET --map ID`: moves one map between
// stores, offline (docs/scale-out.md, "Moving a map"). SOURCE is a SQLite
// file (`mapd --db`, or DIR/<id>.db of `--data-dir`) or a PostgreSQL
// database (`--from-map` names the map); TARGET is a PostgreSQL database, a
// `--data-dir` directory, or a new SQLite file. The copy is
// storage::CopyMap's: observation ids and ties kept, other ids renumbered.
//
// Nothing serves the map while it moves: the source is locked (its file's
// lock, or its lease), and the target appears only when the copy is
// complete and verified (a PostgreSQL map stays "importing", unlisted and
// unserved, until then; a file is written under a temporary name and
// linked into place). A failed copy leaves no map behind.
//
// This is mapd's, not mapctl's: mapctl speaks only the API, and a migration
// works on the databases themselves, next to them, like `mapd token`.
#ifndef MAPD_MAPD_MIGRATE_COMMAND_H_
#define MAPD_MAPD_MIGRATE_COMMAND_H_

#include <CLI/CLI.hpp>
#include <functional>

namespace mapd {

// Adds `migrate` and its flags to `app`; when the command line picks it,
// `*action` is set, which runs it and returns the exit code: 0 copied,
// 1 refused or failed (the message on stderr).
void AddMigrateCommand(CLI::App* app, std::function<int()>* action);

}  // namespace mapd

#endif  // MAPD_MAPD_MIGRATE_COMMAND_H_
