// The mapctl subcommands, declared to CLI11 (client/cli.h). Each run returns
// an ExitCode.
#ifndef MAPD_CLIENT_COMMANDS_H_
#define MAPD_CLIENT_COMMANDS_H_

#include <string>
#include <string_view>
#include <vector>

#include "client/cli.h"
#include "client/robot/robot_client.h"
#include "client/voxel_render.h"
#include "geometry/rigid3.h"

namespace mapd::client {

// Each adds its subcommands, their flags (with the defaults the code uses)
// and their help to `app`; the one the command line picks sets `*action`.
//
// commands_map.cc: status, robots, features (reading the map)
void AddMapCommands(CLI::App* app, Action* action);
// commands_watch.cc: watch (the live change feed of the map)
void AddWatchCommand(CLI::App* app, Action* action);
// commands_ingest.cc: ingest, simulate (writing observations)
void AddIngestCommands(CLI::App* app, Action* action);
// Shared by ingest, simulate and replay (commands_ingest.cc): totals of
// several streams, their one-line summary, and a UTC time for default
// session names (20261205T183707Z).
void Add(const robot::IngestCounts& c, robot::IngestCounts* total);
std::string Summary(const robot::IngestCounts& c);
std::string UtcStampForName();
// commands_replay.cc: replay (recorded robots through the robot library)
void AddReplayCommand(CLI::App* app, Action* action);
// commands_submap.cc: submaps, submap upload|get|delete, global-map (voxel submaps)
void AddSubmapCommands(CLI::App* app, Action* action);
// commands_submap_tools.cc: submap info|crop|transform (OctoMap files and
// stored submaps), added to the `submap` command
void AddSubmapToolCommands(CLI::App* submap, Action* action);
// commands_merge.cc: merge, merge show|approve|reject, merges
void AddMergeCommands(CLI::App* app, Action* action);
// commands_export.cc: occupancy-grid (ROS map_server files), trails (GeoJSON)
void AddExportCommands(CLI::App* app, Action* action);
// commands_auth.cc: token create|list|revoke, audit, whoami
void AddAuthCommands(CLI::App* app, Action* action);
// commands_render.cc: render (top-down renderings of OctoMap files)
void AddRenderCommand(CLI::App* app, Action* action);

// Reads a DataChunk stream (GetSubmap, GetGlobalMap) to its end: the file's
// bytes, and the info of the first message.
grpc::Status ReadChunks(grpc::ClientReader<mapserver::v1::DataChunk>* reader, std::string* data,
                        mapserver::v1::SubmapInfo* info,
                        mapserver::v1::GlobalMapInfo* global = nullptr);

// "XMIN,YMIN,XMAX,YMAX" -> bbox (features, watch); false with `*error` set
// (naming --bbox) otherwise.
bool ParseBbox(const std::string& text, mapserver::v1::BoundingBox2* out, std::string* error);

// Shared by render, `merge --render` and `global-map --render`. Each returns
// kContinue to go on, or the exit code to end with (the error printed).
//
// Checks an output name (.png or .svg) before any work is done, and that
// mapctl was built with voxel support.
int CheckRenderOutput(const std::string& command, const std::string& path, ImageFormat* format);
// Parses OctoMap `bytes` (untrusted) and appends them as a layer named `what`
// in the next colour. A malformed file is kExitUsage, like any bad input file.
int AddRenderLayer(const std::string& command, const std::string& what, std::string_view bytes,
                   const geometry::Rigid3& T_view_layer, std::vector<VoxelLayer>* layers);
// Renders and writes `path`; prints one line saying what was written. Returns
// kExitOk or kExitFailed.
int WriteRendering(const std::string& command, const std::vector<VoxelLayer>& layers,
                   const std::string& path, ImageFormat format, const RenderOptions& options = {});

}  // namespace mapd::client

#endif  // MAPD_CLIENT_COMMANDS_H_
