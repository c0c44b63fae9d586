// GET /api/global-map.png: the global map (the union of the placed submaps,
// service/global_map_builder.h) seen from above, drawn
// with cairo: one pixel per voxel column (at most kMaxPixels on a side,
// columns binned beyond), the highest occupied voxel's height as its
// brightness. 404 before any submap is placed in the map frame. Rendered per request;
// the page asks only when the map changes.
#include <cairo.h>

#include <algorithm>
#include <cmath>
#include <string>

#include "voxel/octree_reader.h"
#include "voxel/voxel_grid.h"
#include "web/http_util.h"

namespace mapd::web {
namespace {

constexpr int kMaxPixels = 1024;

cairo_status_t Append(void* closure, const unsigned char* data, unsigned int length) {
  static_cast<std::string*>(closure)->append(reinterpret_cast<const char*>(data), length);
  return CAIRO_STATUS_SUCCESS;
}

StatusOr<std::string> TopView(const voxel::VoxelGrid& grid) {
  const voxel::VoxelKey& lo = grid.min_key();
  const voxel::VoxelKey& hi = grid.max_key();
  const int nx = hi.x() - lo.x() + 1, ny = hi.y() - lo.y() + 1;
  const int bin = std::max(1, (std::max(nx, ny) + kMaxPixels - 1) / kMaxPixels);
  const int w = (nx + bin - 1) / bin, h = (ny + bin - 1) / bin;
  std::vector<int> top(static_cast<size_t>(w) * h, lo.z() - 1);
  for (const voxel::VoxelKey& k : grid.occupied_keys()) {
    // Image rows grow downwards, y upwards.
    int& t = top[static_cast<size_t>((hi.y() - k.y()) / bin) * w + (k.x() - lo.x()) / bin];
    t = std::max(t, k.z());
  }
  cairo_surface_t* surface = cairo_image_surface_create(CAIRO_FORMAT_RGB24, w, h);
  unsigned char* pixels = cairo_image_surface_get_data(surface);
  const int stride = cairo_image_surface_get_stride(surface);
  const double span = std::max(1, hi.z() - lo.z());
  for (int row = 0; row < h; ++row) {
    auto* line = reinterpret_cast<uint32_t*>(pixels + static_cast<ptrdiff_t>(row) * stride);
    for (int col = 0; col < w; ++col) {
      const int t = top[static_cast<size_t>(row) * w + col];
      if (t < lo.z()) {
        line[col] = 0x202020;  // no occupied voxel in this column
        continue;
      }
      const auto v = static_cast<uint32_t>(80 + 175 * (t - lo.z()) / span);
      line[col] = (v / 2) << 16 | v << 8 | v;  // brighter = higher, a cyan tint
    }
  }
  cairo_surface_mark_dirty(surface);
  std::string png;
  const cairo_status_t s = cairo_surface_write_to_png_stream(surface, Append, &png);
  cairo_surface_destroy(surface);
  if (s != CAIRO_STATUS_SUCCESS)
    return Status::Internal(std::string("PNG encoding failed: ") + cairo_status_to_string(s));
  return png;
}

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
  StatusOr<std::string> png = TopView(*grid);
  if (!png.ok()) return SendError(res, png.status());
  res.set_header("X-Resolution-M", std::to_string(grid->resolution()));
  res.set_header("X-Global-Map-Version", std::to_string(global->version));
  res.set_header("X-Origin-M", std::to_string(grid->min_corner().x()) + "," +
                                   std::to_string(grid->max_corner().y()));
  res.set_content(*png, "image/png");
}

}  // namespace mapd::web
