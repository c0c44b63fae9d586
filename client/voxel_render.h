// Top-down renderings of voxel maps, for an operator to judge a merge by eye:
// each layer (a submap, a file) is drawn in its own colour after its own
// transform, so walls of two submaps that line up after a merge fall on the
// same pixels and show in the mixed colour. Pure functions: no I/O, no gRPC.
//
// Picture: x to the right, y up (north up), one pixel per pixel_m square of
// the view frame's x-y plane; each pixel shows the highest occupied voxel
// above it (brighter = higher, over the 1st..99th percentile of heights), a scale bar in metres and
// a legend naming the layers.
#ifndef MAPD_CLIENT_VOXEL_RENDER_H_
#define MAPD_CLIENT_VOXEL_RENDER_H_

#include <cstddef>
#include <string>
#include <vector>

#include "client/rgb_image.h"
#include "common/status.h"
#include "geometry/rigid3.h"

namespace mapd::client {

struct VoxelLayer {
  std::string label;                       // legend text: "submap 3 (robot r1)", a file name
  Rgb colour;                              // e.g. LayerColour(index)
  double resolution_m = 0.1;               // voxel edge; each voxel covers this square
  std::vector<Eigen::Vector3d> centres_m;  // occupied voxel centres, layer frame
  geometry::Rigid3 T_view_layer;           // maps the layer's points into the picture's frame
};

// Well-separated colours for layer `index` (they repeat after 8).
Rgb LayerColour(size_t index);

struct RenderOptions {
  double pixel_m = 0.0;   // metres per pixel; 0 = the finest layer resolution
  int max_map_px = 2048;  // longest side of the map area in pixels; pixel_m grows to fit
  // With pixel_m = 0, a small map is magnified until its longest side has at
  // least this many pixels (an 8 m room of 10 cm voxels would be 80 px).
  int min_map_px = 512;
  int margin_px = 12;
  int text_scale = 2;  // text size: the labels' font is 9 px per step (18 px by default)
  Rgb background{255, 255, 255};

  // InvalidArgument naming the field: pixel_m finite and >= 0, max_map_px in
  // [16, 16384], min_map_px in [1, max_map_px], margin_px in [0, 1000],
  // text_scale in [1, 8].
  Status Validate() const;
};

// The map area before scale bar and legend.
struct TopView {
  RgbImage map;        // background where no layer has a voxel
  double pixel_m = 0;  // metres per pixel
  double x_min_m = 0, x_max_m = 0, y_min_m = 0, y_max_m = 0;  // area covered, view frame
  double z_min_m = 0, z_max_m = 0;  // height range of the shading: 1st..99th percentile
  size_t voxels = 0;                // voxels drawn, all layers

  // The pixel (column, row) holding view-frame point (x, y), metres; may lie outside the map.
  void MetresToPixel(double x, double y, int* col, int* row) const;
};

// Draws the layers; bounds fit every voxel of every layer. InvalidArgument for
// bad options, no layer, no voxel at all, a layer resolution that is not
// finite and > 0, or a point that is not finite after its transform.
StatusOr<TopView> RenderTopView(const std::vector<VoxelLayer>& layers,
                                const RenderOptions& options);

// Scale bar length in metres for a map `width_m` wide: the largest 1, 2 or 5
// times a power of ten that is at most 40% of the width.
double ScaleBarLengthM(double width_m);

enum class ImageFormat { kPng, kSvg };
// From the extension (.png, .svg, any case); false otherwise.
bool ImageFormatFromPath(const std::string& path, ImageFormat* format);

// The complete picture (map, scale bar, caption, legend), drawn by cairo, as a
// PNG file, or as an SVG file embedding the map as a PNG with vector scale bar
// and legend (labels as glyph outlines, in their real case). Internal if cairo fails.
StatusOr<std::string> RenderVoxelImage(const std::vector<VoxelLayer>& layers,
                                       const RenderOptions& options, ImageFormat format);

}  // namespace mapd::client

#endif  // MAPD_CLIENT_VOXEL_RENDER_H_
