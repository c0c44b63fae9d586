// mapctl render, and the rendering shared with `merge --render` and
// `global-map --render`: OctoMap bytes -> safe parser -> top-down PNG/SVG.
#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "client/commands.h"
#include "client/text_util.h"
#include "client/voxel_loader.h"

namespace mapd::client {
namespace {

// Same cap as the server's octree reader: a bigger file is refused unread.
constexpr uintmax_t kMaxFileBytes = uintmax_t{256} << 20;

const char kRenderHelp[] =
    "Usage: mapctl render FILE.bt [FILE2.bt ...] -o OUT.png|OUT.svg [--pixel M] [--max-size PX]\n"
    "Draws OctoMap files (.bt or .ot) seen from above, each file a layer in its own colour,\n"
    "in its own frame: brighter = higher (the highest occupied voxel per pixel), where layers\n"
    "overlap their colours mix. A scale bar in metres and a legend naming the files.\n"
    "Files are checked by the same parser as the server's before anything is drawn.\n"
    "  -o          output file; the format follows the extension (.png or .svg)\n"
    "  --pixel     metres per pixel (default: the finest voxel size)\n"
    "  --max-size  longest side of the map in pixels (default 2048; --pixel grows to fit)\n";

std::string LoadErrorCode(const Status& status) { return ::mapd::StatusCodeName(status.code()); }

}  // namespace

int CheckRenderOutput(const std::string& command, const std::string& path, ImageFormat* format) {
  if (!ImageFormatFromPath(path, format)) {
    return UsageError(command, "cannot tell the image format of '" + path + "': use a .png or .svg name");
  }
  return kContinue;
}

int AddRenderLayer(const std::string& command, const std::string& what, std::string_view bytes,
                   const RigidTransform& T_view_layer, std::vector<VoxelLayer>* layers) {
  StatusOr<LoadedVoxels> voxels = LoadOccupiedVoxels(bytes);
  if (!voxels.ok()) {
    PrintError(command + ": " + what + ": " + voxels.status().message() + " (" + LoadErrorCode(voxels.status()) +
               ")");
    return voxels.status().code() == StatusCode::kUnimplemented ? kExitFailed : kExitUsage;
  }
  VoxelLayer layer;
  layer.label = Printf("%s: %zu voxels, %.3g m", what.c_str(), voxels->centres_m.size(), voxels->resolution_m);
  layer.colour = LayerColour(layers->size());
  layer.resolution_m = voxels->resolution_m;
  layer.centres_m = std::move(voxels->centres_m);
  layer.T_view_layer = T_view_layer;
  layers->push_back(std::move(layer));
  return kContinue;
}

int WriteRendering(const std::string& command, const std::vector<VoxelLayer>& layers, const std::string& path,
                   ImageFormat format, const RenderOptions& options) {
  StatusOr<std::string> image = RenderVoxelImage(layers, options, format);
  if (!image.ok()) {
    PrintError(command + ": cannot render " + path + ": " + image.status().message());
    return kExitFailed;
  }
  std::string error;
  if (!WriteOutput(path, image.value(), &error)) {
    PrintError(command + ": " + error);
    return kExitFailed;
  }
  size_t voxels = 0;
  for (const VoxelLayer& layer : layers) voxels += layer.centres_m.size();
  std::printf("rendered %zu layer%s (%zu voxels) to %s\n", layers.size(), layers.size() == 1 ? "" : "s", voxels,
              path.c_str());
  return kExitOk;
}

int RunRender(const Context& /*ctx*/, const CommandArgs& args) {
  Args flags;
  const std::vector<FlagSpec> specs = {{"-o", true}, {"--output", true}, {"--pixel", true}, {"--max-size", true}};
  if (int rc = ParseCommandArgs("render", kRenderHelp, args, specs, &flags); rc != kContinue) return rc;
  const std::string output = flags.Get("-o", flags.Get("--output"));
  if (output.empty()) return UsageError("render", "needs -o OUT.png or -o OUT.svg");
  if (flags.positionals().empty()) return UsageError("render", "wants one or more OctoMap files");
  RenderOptions options;
  if (flags.Has("--pixel") && (!ParseDouble(flags.Get("--pixel"), &options.pixel_m) || options.pixel_m <= 0)) {
    return UsageError("render", "--pixel wants metres > 0, got '" + flags.Get("--pixel") + "'");
  }
  if (flags.Has("--max-size")) {
    uint64_t px = 0;
    if (!ParseUint(flags.Get("--max-size"), &px) || px < 16 || px > 16384) {
      return UsageError("render", "--max-size wants pixels in [16, 16384], got '" + flags.Get("--max-size") + "'");
    }
    options.max_map_px = static_cast<int>(px);
    options.min_map_px = std::min(options.min_map_px, options.max_map_px);
  }
  ImageFormat format;
  if (int rc = CheckRenderOutput("render", output, &format); rc != kContinue) return rc;

  std::vector<VoxelLayer> layers;
  for (const std::string& path : flags.positionals()) {
    std::error_code ec;
    const uintmax_t size = std::filesystem::file_size(path, ec);
    if (!ec && size > kMaxFileBytes) {
      PrintError(Printf("render: %s: %ju bytes, more than the %ju the reader accepts", path.c_str(), size,
                        kMaxFileBytes));
      return kExitFailed;
    }
    std::ifstream file(path, std::ios::binary);
    if (!file) {
      PrintError("render: cannot open " + path + ": " + std::strerror(errno));
      return kExitFailed;
    }
    std::stringstream bytes;
    bytes << file.rdbuf();
    const std::string name = std::filesystem::path(path).filename().string();
    if (int rc = AddRenderLayer("render", name, bytes.str(), RigidTransform(), &layers); rc != kContinue) return rc;
  }
  return WriteRendering("render", layers, output, format, options);
}

}  // namespace mapd::client
