// `mapd token create|list|revoke --db FILE ...` (or --store CONNINFO for
// PostgreSQL): token management offline, on the database directly. Access
// to the database is the trust root: it makes the first admin token
// (bootstrap) and recovers from a lost one.
// The secret of a new token is printed once, on stdout.
#ifndef MAPD_MAPD_TOKEN_COMMAND_H_
#define MAPD_MAPD_TOKEN_COMMAND_H_

#include <CLI/CLI.hpp>
#include <functional>

namespace mapd {

// Adds `token create|list|revoke` and their flags to `app`; the one the
// command line picks sets `*action`, which returns the exit code: 0 ok,
// 1 the database refused.
void AddTokenCommand(CLI::App* app, std::function<int()>* action);

}  // namespace mapd

#endif  // MAPD_MAPD_TOKEN_COMMAND_H_
