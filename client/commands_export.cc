// mapctl occupancy-grid | trails: the map as other tools want it (a ROS
// map_server grid, the robots' paths as GeoJSON).
#include <cmath>
#include <cstdio>

#include "client/commands.h"
#include "client/format.h"
#include "client/occupancy_grid.h"
#include "client/text_util.h"
#include "client/voxel_loader.h"

namespace mapd::client {
namespace {

namespace pb = mapserver::v1;

struct GridOptions {
  std::string output;
  double z_min = 0.1;
  double z_max = 1.8;
  double resolution = 0;
  bool lines = false;
  std::vector<std::string> source{"global"};
};

struct TrailsOptions {
  std::string output = "-";
  std::string robot;
  uint32_t max_poses = 0;
};

bool EndsWith(const std::string& s, const std::string& suffix) {
  return s.size() >= suffix.size() &&
         s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

// The voxel map asked for: the global map, or submap `id`. Its bytes in `*data`.
int FetchVoxelMap(const Context& ctx, bool global, uint64_t id, std::string* data) {
  pb::SubmapInfo info;
  auto call = ctx.NewStreamContext();
  grpc::Status status;
  if (global) {
    status = ReadChunks(ctx.stub->GetGlobalMap(call.get(), pb::GetGlobalMapRequest()).get(), data,
                        &info);
    if (status.error_code() == grpc::StatusCode::NOT_FOUND) {
      PrintError(
          "occupancy-grid: no global map yet: it is made by the first accepted merge "
          "(mapctl merge ID ID...), or use --source submap ID");
      return kExitFailed;
    }
  } else {
    pb::GetSubmapRequest request;
    request.set_id(id);
    status = ReadChunks(ctx.stub->GetSubmap(call.get(), request).get(), data, &info);
  }
  if (!status.ok()) {
    return ReportRpcError(
        ctx,
        global ? std::string("occupancy-grid: GetGlobalMap")
               : Printf("occupancy-grid: GetSubmap %llu", static_cast<unsigned long long>(id)),
        status);
  }
  return kContinue;
}

// The fused walls (map frame) as segments to draw.
int FetchLines(const Context& ctx, std::vector<GridLine>* lines) {
  auto call = ctx.NewCallContext();
  std::unique_ptr<grpc::ClientReader<pb::FeatureMapPage>> reader =
      ctx.stub->GetFeatureMap(call.get(), pb::FeatureMapRequest());
  pb::FeatureMapPage page;
  while (reader->Read(&page)) {
    for (const pb::FusedFeature& f : page.features())
      lines->push_back({f.a().x(), f.a().y(), f.b().x(), f.b().y()});
  }
  const grpc::Status status = reader->Finish();
  if (!status.ok()) return ReportRpcError(ctx, "occupancy-grid: GetFeatureMap", status);
  return kContinue;
}

int RunOccupancyGrid(const Context& ctx, const GridOptions& flags) {
  // NAME, NAME.yaml or NAME.pgm all name the pair.
  std::string name = flags.output;
  for (const char* ext : {".yaml", ".pgm"}) {
    if (EndsWith(name, ext)) name.resize(name.size() - std::string(ext).size());
  }
  if (name.empty() || EndsWith(name, "/"))
    return UsageError("occupancy-grid", "-o wants a file name, got '" + flags.output + "'");
  if (!(flags.z_min < flags.z_max)) {
    return UsageError("occupancy-grid",
                      Printf("--z-min (%g) must be below --z-max (%g)", flags.z_min, flags.z_max));
  }
  bool global = true;
  uint64_t id = 0;
  // "submap 7" as two words, or as one: "submap 7" quoted, submap:7, submap=7.
  std::vector<std::string> source = flags.source;
  if (source.size() == 1) {
    const size_t cut = source[0].find_first_of(" :=");
    if (cut != std::string::npos) {
      const size_t rest = source[0].find_first_not_of(" :=", cut);
      source = {source[0].substr(0, cut),
                rest == std::string::npos ? std::string() : source[0].substr(rest)};
    }
  }
  if (source.size() == 2 && source[0] == "submap") {
    double v = 0;
    if (!ParseDouble(source[1], &v) || v < 1 || v != std::floor(v) || v > 9e15) {
      return UsageError(
          "occupancy-grid",
          "--source submap wants an id (a whole number > 0), got '" + source[1] + "'");
    }
    global = false;
    id = static_cast<uint64_t>(v);
    if (flags.lines) {
      // A submap is in its robot's session frame, the fused walls in the map frame.
      return UsageError("occupancy-grid",
                        "--lines draws the map-frame walls: use it with --source global only");
    }
  } else if (!(source.size() == 1 && source[0] == "global")) {
    return UsageError(
        "occupancy-grid", "--source wants 'global' or 'submap ID' (also submap:ID), got '" +
                              [&flags] {
                                std::string text;
                                for (const std::string& w : flags.source)
                                  text += (text.empty() ? "" : " ") + w;
                                return text;
                              }() +
                              "'");
  }

  std::string data;
  if (int rc = FetchVoxelMap(ctx, global, id, &data); rc != kContinue) return rc;
  std::vector<GridLine> lines;
  if (flags.lines) {
    if (int rc = FetchLines(ctx, &lines); rc != kContinue) return rc;
  }
  StatusOr<voxel::VoxelGrid> voxels = LoadVoxelGrid(data);
  if (!voxels.ok()) {
    PrintError("occupancy-grid: the server's voxel map does not parse: " +
               voxels.status().ToString());
    return kExitFailed;
  }
  OccupancyGridOptions options;
  options.z_min_m = flags.z_min;
  options.z_max_m = flags.z_max;
  options.resolution_m = flags.resolution;
  StatusOr<OccupancyGrid> grid = BuildOccupancyGrid(*voxels, options, lines);
  if (!grid.ok()) {
    PrintError("occupancy-grid: " + grid.status().message());
    return kExitFailed;
  }

  const std::string pgm = name + ".pgm", yaml = name + ".yaml";
  const size_t slash = pgm.find_last_of('/');
  const std::string image = slash == std::string::npos ? pgm : pgm.substr(slash + 1);
  std::string error;
  if (!WriteOutput(pgm, EncodePgm(*grid), &error) ||
      !WriteOutput(yaml, EncodeMapYaml(*grid, image), &error)) {
    PrintError("occupancy-grid: " + error);
    return kExitFailed;
  }
  size_t counts[3] = {0, 0, 0};
  for (Cell c : grid->cells) ++counts[static_cast<int>(c)];
  std::printf(
      "wrote %s and %s: %d x %d cells of %g m, origin (%g, %g), %zu occupied, %zu free, %zu "
      "unknown%s\n",
      pgm.c_str(), yaml.c_str(), grid->width, grid->height, grid->resolution_m, grid->origin_x_m,
      grid->origin_y_m, counts[static_cast<int>(Cell::kOccupied)],
      counts[static_cast<int>(Cell::kFree)], counts[static_cast<int>(Cell::kUnknown)],
      flags.lines ? Printf(", %zu fused lines drawn", lines.size()).c_str() : "");
  return kExitOk;
}

int RunTrails(const Context& ctx, const TrailsOptions& flags) {
  pb::GetTrailsRequest request;
  request.set_robot_id(flags.robot);
  request.set_max_poses_per_session(flags.max_poses);
  auto call = ctx.NewStreamContext();
  std::unique_ptr<grpc::ClientReader<pb::SessionTrail>> reader =
      ctx.stub->GetTrails(call.get(), request);
  std::vector<pb::SessionTrail> trails;
  pb::SessionTrail trail;
  while (reader->Read(&trail)) trails.push_back(trail);
  const grpc::Status status = reader->Finish();
  if (!status.ok()) return ReportRpcError(ctx, "trails", status);
  std::string error;
  if (!WriteOutput(flags.output, FormatTrailsGeoJson(trails), &error)) {
    PrintError("trails: " + error);
    return kExitFailed;
  }
  if (flags.output != "-") {
    size_t untied = 0;
    for (const pb::SessionTrail& t : trails) untied += t.frame_tied() ? 0 : 1;
    std::printf("wrote %zu session trails (%zu not tied to the map frame) to %s\n", trails.size(),
                untied, flags.output.c_str());
  }
  return kExitOk;
}

}  // namespace

void AddExportCommands(CLI::App* app, Action* action) {
  CLI::App* grid = app->add_subcommand(
      "occupancy-grid", "a 2D occupancy grid for ROS map_server (-o NAME: NAME.pgm, NAME.yaml)");
  grid->footer(
      "Cuts the merged global map (or one submap) between two heights into a 2D grid:\n"
      "a cell is occupied if an occupied voxel of the band lies in it, free if only free\n"
      "voxels do, else unknown. Writes NAME.pgm (binary PGM: 254 free, 0 occupied, 205\n"
      "unknown; the top row is the largest y) and NAME.yaml (image, resolution, origin of\n"
      "the lower-left pixel, negate 0, occupied_thresh 0.65, free_thresh 0.196, trinary),\n"
      "as ROS map_server and nav2's map_server read them.");
  auto g = BindCommand(grid, action, RunOccupancyGrid);
  grid->add_option("-o,--output", g->output, "NAME (or NAME.yaml / NAME.pgm)")->required();
  grid->add_option("--z-min", g->z_min, "lowest voxel centre height of the band, metres")
      ->capture_default_str();
  grid->add_option("--z-max", g->z_max, "highest voxel centre height of the band, metres")
      ->capture_default_str();
  grid->add_option("--resolution", g->resolution, "cell edge in metres (default: the voxel map's)")
      ->check(PositiveReal());
  grid->add_flag("--lines", g->lines,
                 "also draw the fused walls (GetFeatureMap, map frame) as occupied cells");
  grid->add_option("--source", g->source,
                   "global (the merged map, default) or submap ID (also submap:ID)")
      ->expected(1, 2);

  CLI::App* trails =
      app->add_subcommand("trails", "the robots' paths as GeoJSON (one line per session)");
  trails->footer(
      "One LineString per robot session through its observations' sensor positions, in the\n"
      "map frame where the session is tied to it (property frame \"map\"), else in the\n"
      "session's own frame (frame \"session\"). Long sessions are thinned evenly.");
  auto t = BindCommand(trails, action, RunTrails);
  trails->add_option("-o,--output", t->output, "write to FILE (- for stdout)")
      ->capture_default_str();
  trails->add_option("--robot", t->robot, "only this robot's sessions");
  trails->add_option("--max-poses", t->max_poses,
                     "poses per session at most (0 = the server's 10000; at most 50000)");
}

}  // namespace mapd::client
