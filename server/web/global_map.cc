// GET /api/global-map.png: the global map (the union of the placed submaps,
// service/global_map_builder.h) seen from above, drawn by the renderer mapctl
// draws merges and files with (client/voxel_render.h): the highest occupied
// voxel of each column, brighter = higher, a scale bar and a legend naming the
// map's version. 404 before any submap is placed in the map frame. Rendered
// per request; the page asks only when the map changes.
#include <string>
#include <vector>

#include "client/voxel_render.h"
#include "voxel/octree_reader.h"
#include "voxel/voxel_grid.h"
#include "web/http_util.h"

namespace mapd::web {
namespace {

constexpr int kMaxPixels = 1024;  // the map area's longest side: the page shows it whole

}  // namespace

void ServeGlobalMap(service::Core* core, httplib::Response& res) {
  StatusOr<storage::GlobalMapRecord> global = core->store().GetGlobalMap(/*with_data=*/true);
  if (!global.ok()) {
    return SendError(res,
                     global.status().code() == StatusCode::kNotFound
                         ? Status::NotFound("no global map yet (no submap placed in the map frame)")
                         : global.status());
  }
  StatusOr<voxel::OcTreePtr> tree = voxel::ReadOctree(global->data);
  if (!tree.ok()) return SendError(res, tree.status());
  StatusOr<voxel::VoxelGrid> grid = voxel::VoxelGrid::FromOcTree(**tree);
  if (!grid.ok()) return SendError(res, grid.status());
  if (grid->empty())
    return SendError(res, Status::NotFound("the global map has no occupied voxel"));
  client::VoxelLayer layer;
  layer.label = "global map, version " + std::to_string(global->version) + ", " +
                std::to_string(global->members.size()) + " submaps";
  layer.colour = client::LayerColour(0);
  layer.resolution_m = grid->resolution();
  layer.centres_m = grid->occupied_centres();
  client::RenderOptions options;
  options.max_map_px = kMaxPixels;
  StatusOr<std::string> png = client::RenderVoxelImage({layer}, options, client::ImageFormat::kPng);
  if (!png.ok()) return SendError(res, png.status());
  res.set_header("X-Resolution-M", std::to_string(grid->resolution()));
  res.set_header("X-Global-Map-Version", std::to_string(global->version));
  res.set_content(*png, "image/png");
}

}  // namespace mapd::web
