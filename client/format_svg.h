// The fused feature map as an SVG drawing (mapctl features --format svg),
// drawn by cairo. Part of the maprender library.
#ifndef MAPD_CLIENT_FORMAT_SVG_H_
#define MAPD_CLIENT_FORMAT_SVG_H_

#include <string>

#include "client/format.h"

namespace mapd::client {

struct SvgOptions {
  double pixels_per_metre = 40;  // the pixel size is clamped to [400, 1600] wide
};
// An SVG drawing fitted to the features: y axis up, a metre grid, one stroked
// path per feature coloured by kind (walls #1f77b4, the rest #d62728) with a
// width growing with support, a scale bar and a legend (text as cairo glyph
// outlines). Empty only if cairo fails (out of memory).
std::string FormatSvg(const FeatureList& features, const SvgOptions& options = {});
// The same with the planes drawn first, as translucent filled paths (the
// ground projection of each boundary, #2ca02c) under the lines; the drawing
// fits both.
std::string FormatSvg(const FeatureList& features, const PlaneList& planes,
                      const SvgOptions& options = {});

}  // namespace mapd::client

#endif  // MAPD_CLIENT_FORMAT_SVG_H_
