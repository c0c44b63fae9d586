// The mapctl subcommands. Each takes the arguments after its name, prints its
// own --help, and returns an ExitCode (client/cli.h).
#ifndef MAPD_CLIENT_COMMANDS_H_
#define MAPD_CLIENT_COMMANDS_H_

#include <string>
#include <string_view>
#include <vector>

#include "client/cli.h"
#include "client/rigid_transform.h"
#include "client/voxel_render.h"

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

// commands_auth.cc: tokens, the audit log, whoami
int RunToken(const Context& ctx, const CommandArgs& args);  // "token create|list|revoke ..."
int RunAudit(const Context& ctx, const CommandArgs& args);
int RunWhoAmI(const Context& ctx, const CommandArgs& args);

// commands_render.cc: top-down renderings of OctoMap files
int RunRender(const Context& ctx, const CommandArgs& args);

// Shared by render, `merge --render` and `global-map --render`. Each returns
// kContinue to go on, or the exit code to end with (the error printed).
//
// Checks an output name (.png or .svg) before any work is done, and that
// mapctl was built with voxel support.
int CheckRenderOutput(const std::string& command, const std::string& path, ImageFormat* format);
// Parses OctoMap `bytes` (untrusted) and appends them as a layer named `what`
// in the next colour. A malformed file is kExitUsage, like any bad input file.
int AddRenderLayer(const std::string& command, const std::string& what, std::string_view bytes,
                   const RigidTransform& T_view_layer, std::vector<VoxelLayer>* layers);
// Renders and writes `path`; prints one line saying what was written. Returns
// kExitOk or kExitFailed.
int WriteRendering(const std::string& command, const std::vector<VoxelLayer>& layers, const std::string& path,
                   ImageFormat format, const RenderOptions& options = {});

}  // namespace mapd::client

#endif  // MAPD_CLIENT_COMMANDS_H_
