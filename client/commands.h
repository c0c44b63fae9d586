// The mapctl subcommands. Each takes the arguments after its name, prints its
// own --help, and returns an ExitCode (client/cli.h).
#ifndef MAPD_CLIENT_COMMANDS_H_
#define MAPD_CLIENT_COMMANDS_H_

#include <string>
#include <vector>

#include "client/cli.h"

namespace mapd::client {

using CommandArgs = std::vector<std::string>;

// commands_map.cc: reading the map
int RunStatus(const Context& ctx, const CommandArgs& args);
int RunRobots(const Context& ctx, const CommandArgs& args);
int RunFeatures(const Context& ctx, const CommandArgs& args);

// commands_ingest.cc: writing observations
int RunIngest(const Context& ctx, const CommandArgs& args);
int RunSimulate(const Context& ctx, const CommandArgs& args);

// commands_submap.cc: voxel submaps and merging
int RunSubmaps(const Context& ctx, const CommandArgs& args);
int RunSubmap(const Context& ctx, const CommandArgs& args);  // "submap upload ..."
int RunMerge(const Context& ctx, const CommandArgs& args);
int RunGlobalMap(const Context& ctx, const CommandArgs& args);

}  // namespace mapd::client

#endif  // MAPD_CLIENT_COMMANDS_H_
