// `mapd token create|list|revoke --db FILE ...`: token management offline,
// on the database file directly. Access to that file is the trust root: it
// makes the first admin token (bootstrap) and recovers from a lost one.
// The secret of a new token is printed once, on stdout.
#ifndef MAPD_MAPD_TOKEN_COMMAND_H_
#define MAPD_MAPD_TOKEN_COMMAND_H_

#include <string>
#include <vector>

namespace mapd {

// `args` are the arguments after "token". Returns the exit code: 0 ok,
// 1 the database refused, 2 usage error.
int RunTokenCommand(const std::vector<std::string>& args);

}  // namespace mapd

#endif  // MAPD_MAPD_TOKEN_COMMAND_H_
