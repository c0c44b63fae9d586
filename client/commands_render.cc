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

struct RenderCommandOptions {
  std::vector<std::string> files;
  std::string output;
  RenderOptions render;
};

std::string LoadErrorCode(const Status& status) { return ::mapd::StatusCodeName(status.code()); }

}  // namespace

int CheckRenderOutput(const std::string& command, const std::string& path, ImageFormat* format) {
  if (!ImageFormatFromPath(path, format)) {
    return UsageError(command,
                      "cannot tell the image format of '" + path + "': use a .png or .svg name");
  }
  return kContinue;
}

int AddRenderLayer(const std::string& command, const std::string& what, std::string_view bytes,
                   const geometry::Rigid3& T_view_layer, std::vector<VoxelLayer>* layers) {
  StatusOr<LoadedVoxels> voxels = LoadOccupiedVoxels(bytes);
  if (!voxels.ok()) {
    PrintError(command + ": " + what + ": " + voxels.status().message() + " (" +
               LoadErrorCode(voxels.status()) + ")");
    return voxels.status().code() == StatusCode::kUnimplemented ? kExitFailed : kExitUsage;
  }
  VoxelLayer layer;
  layer.label = Printf("%s: %zu voxels, %.3g m", what.c_str(), voxels->centres_m.size(),
                       voxels->resolution_m);
  layer.colour = LayerColour(layers->size());
  layer.resolution_m = voxels->resolution_m;
  layer.centres_m = std::move(voxels->centres_m);
  layer.T_view_layer = T_view_layer;
  layers->push_back(std::move(layer));
  return kContinue;
}

int WriteRendering(const std::string& command, const std::vector<VoxelLayer>& layers,
                   const std::string& path, ImageFormat format, const RenderOptions& options) {
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
  std::printf("rendered %zu layer%s (%zu voxels) to %s\n", layers.size(),
              layers.size() == 1 ? "" : "s", voxels, path.c_str());
  return kExitOk;
}

namespace {

int RunRender(const Context& /*ctx*/, const RenderCommandOptions& flags) {
  const std::string& output = flags.output;
  RenderOptions options = flags.render;
  options.min_map_px = std::min(options.min_map_px, options.max_map_px);
  ImageFormat format;
  if (int rc = CheckRenderOutput("render", output, &format); rc != kContinue) return rc;

  std::vector<VoxelLayer> layers;
  for (const std::string& path : flags.files) {
    std::error_code ec;
    const uintmax_t size = std::filesystem::file_size(path, ec);
    if (!ec && size > kMaxFileBytes) {
      PrintError(Printf("render: %s: %ju bytes, more than the %ju the reader accepts", path.c_str(),
                        size, kMaxFileBytes));
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
    if (int rc = AddRenderLayer("render", name, bytes.str(), geometry::Rigid3(), &layers);
        rc != kContinue)
      return rc;
  }
  return WriteRendering("render", layers, output, format, options);
}

}  // namespace

void AddRenderCommand(CLI::App* app, Action* action) {
  CLI::App* render = app->add_subcommand(
      "render", "draw OctoMap files from above as PNG or SVG (no server needed)");
  render->footer(
      "Draws OctoMap files (.bt or .ot) seen from above, each file a layer in its own colour,\n"
      "in its own frame: brighter = higher (the highest occupied voxel per pixel), where layers\n"
      "overlap their colours mix. A scale bar in metres and a legend naming the files.\n"
      "Files are checked by the same parser as the server's before anything is drawn.");
  auto r = BindCommand(render, action, RunRender);
  render->add_option("FILE", r->files, "OctoMap files, one layer each")->required();
  render
      ->add_option("-o,--output", r->output, "OUT.png or OUT.svg: the format follows the extension")
      ->required();
  render
      ->add_option("--pixel", r->render.pixel_m,
                   "metres per pixel (default: the finest voxel size)")
      ->check(PositiveReal());
  render
      ->add_option("--max-size", r->render.max_map_px,
                   "longest side of the map in pixels (--pixel grows to fit)")
      ->capture_default_str()
      ->check(CLI::Range(16, 16384));
}

}  // namespace mapd::client
