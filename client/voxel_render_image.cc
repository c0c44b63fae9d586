// RenderVoxelImage: a TopView framed by a scale bar, a caption and a legend,
// drawn by cairo on an image surface (PNG) or an SVG surface (the map embedded
// as a PNG, the rest as vector shapes and text). Both share one layout in
// pixels and one drawing function.
#include <algorithm>
#include <cmath>

#include "client/cairo_canvas.h"
#include "client/text_util.h"
#include "client/voxel_render.h"

namespace mapd::client {
namespace {

const Rgb kInk{20, 20, 20};
const Rgb kFrame{190, 190, 190};
constexpr char kFontFamily[] = "sans-serif";

struct Line {
  int y = 0;  // top of the line, px
  std::string text;
  bool swatch = false;  // a coloured square before the text
  Rgb colour;
};

struct Layout {
  int width = 0, height = 0;
  int map_x = 0, map_y = 0;
  int bar_y = 0, bar_px = 0, bar_h = 0;
  std::string bar_label;
  int text_scale = 1, line_h = 0, swatch_px = 0;
  double font_px = 0, ascent_px = 0;
  std::vector<Line> lines;  // caption, then the legend
};

std::string FormatMetres(double m) { return m >= 1 ? Printf("%g m", m) : Printf("%g cm", m * 100); }

void SelectFont(cairo_t* cr, double size_px) {
  cairo_select_font_face(cr, kFontFamily, CAIRO_FONT_SLANT_NORMAL, CAIRO_FONT_WEIGHT_NORMAL);
  cairo_set_font_size(cr, size_px);
}

Layout MakeLayout(const TopView& view, const std::vector<VoxelLayer>& layers,
                  const RenderOptions& options) {
  // Text is measured on a scratch surface with the font the drawing uses.
  Canvas scratch = Canvas::Raster(1, 1);
  cairo_t* cr = scratch.cr();
  Layout l;
  const int s = options.text_scale, m = options.margin_px;
  l.text_scale = s;
  l.font_px = 9.0 * s;
  SelectFont(cr, l.font_px);
  cairo_font_extents_t font;
  cairo_font_extents(cr, &font);
  l.ascent_px = font.ascent;
  l.line_h = std::max(static_cast<int>(std::ceil(font.height)), 11 * s);
  l.swatch_px = 7 * s;
  auto text_width = [cr](const std::string& text) {
    cairo_text_extents_t e;
    cairo_text_extents(cr, text.c_str(), &e);
    return static_cast<int>(std::ceil(e.x_advance));
  };
  l.map_x = m;
  l.map_y = m;
  const int map_bottom = m + view.map.height();

  const double bar_m = ScaleBarLengthM(view.x_max_m - view.x_min_m);
  l.bar_px = std::max(1, static_cast<int>(std::lround(bar_m / view.pixel_m)));
  l.bar_h = 2 * s + 2;
  l.bar_y = map_bottom + m;
  l.bar_label = FormatMetres(bar_m);
  int content_w = std::max(view.map.width(), l.bar_px + 3 * s + text_width(l.bar_label));

  int y = l.bar_y + std::max(l.bar_h, l.line_h) + m / 2 + s;
  auto add = [&](std::string text, bool swatch, Rgb colour) {
    const int w = (swatch ? l.swatch_px + 3 * s : 0) + text_width(text);
    content_w = std::max(content_w, w);
    l.lines.push_back({y, std::move(text), swatch, colour});
    y += l.line_h;
  };
  add(Printf("top view, %.3g m/px, brighter = higher (z %.2f .. %.2f m)", view.pixel_m,
             view.z_min_m, view.z_max_m),
      false, kInk);
  for (const VoxelLayer& layer : layers) add(layer.label, true, layer.colour);
  if (layers.size() > 1) add("mixed colour: layers overlap", false, kInk);

  l.width = content_w + 2 * m;
  l.height = y + m;
  return l;
}

void FillRect(cairo_t* cr, int x, int y, int w, int h, Rgb colour) {
  SetColour(cr, colour);
  cairo_rectangle(cr, x, y, w, h);
  cairo_fill(cr);
}

// Text with its top at `top_y` (the layout's lines are placed by their top).
void DrawText(cairo_t* cr, const Layout& l, int x, int top_y, const std::string& text) {
  SetColour(cr, kInk);
  cairo_move_to(cr, x, top_y + l.ascent_px);
  cairo_show_text(cr, text.c_str());
}

void Draw(cairo_t* cr, const TopView& view, const Layout& l, const RenderOptions& options) {
  FillRect(cr, 0, 0, l.width, l.height, options.background);
  // A thin frame around the map area shows its extent even where it is empty.
  FillRect(cr, l.map_x - 1, l.map_y - 1, view.map.width() + 2, view.map.height() + 2, kFrame);
  // The map pixel for pixel: no smoothing when a viewer scales it.
  CairoSurface map = ToSurface(view.map);
  cairo_set_source_surface(cr, map.get(), l.map_x, l.map_y);
  cairo_pattern_set_filter(cairo_get_source(cr), CAIRO_FILTER_NEAREST);
  cairo_rectangle(cr, l.map_x, l.map_y, view.map.width(), view.map.height());
  cairo_fill(cr);

  SelectFont(cr, l.font_px);
  FillRect(cr, l.map_x, l.bar_y, l.bar_px, l.bar_h, kInk);
  DrawText(cr, l, l.map_x + l.bar_px + 3 * l.text_scale, l.bar_y, l.bar_label);
  for (const Line& line : l.lines) {
    int x = l.map_x;
    if (line.swatch) {
      FillRect(cr, x, line.y + static_cast<int>(l.ascent_px) - l.swatch_px, l.swatch_px,
               l.swatch_px, line.colour);
      x += l.swatch_px + 3 * l.text_scale;
    }
    DrawText(cr, l, x, line.y, line.text);
  }
}

}  // namespace

StatusOr<std::string> RenderVoxelImage(const std::vector<VoxelLayer>& layers,
                                       const RenderOptions& options, ImageFormat format) {
  StatusOr<TopView> view = RenderTopView(layers, options);
  if (!view.ok()) return view.status();
  const Layout layout = MakeLayout(*view, layers, options);
  if (format == ImageFormat::kPng) {
    Canvas canvas = Canvas::Raster(layout.width, layout.height);
    Draw(canvas.cr(), *view, layout, options);
    return canvas.Png();
  }
  Canvas canvas = Canvas::Svg(layout.width, layout.height);
  Draw(canvas.cr(), *view, layout, options);
  return canvas.FinishSvg();
}

}  // namespace mapd::client
