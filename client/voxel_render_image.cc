// RenderVoxelImage: a TopView framed by a scale bar, a caption and a legend,
// as PNG (text in the 5x7 bitmap font) or SVG (the map as an embedded PNG,
// the rest as vector shapes and text). Both share one layout in pixels.
#include <algorithm>
#include <cmath>

#include "client/bitmap_font.h"
#include "client/png_writer.h"
#include "client/text_util.h"
#include "client/voxel_render.h"

namespace mapd::client {
namespace {

const Rgb kInk{20, 20, 20};

struct Line {
  int y = 0;             // top of the line, px
  std::string text;
  bool swatch = false;   // a coloured square before the text
  Rgb colour;
};

struct Layout {
  int width = 0, height = 0;
  int map_x = 0, map_y = 0;
  int bar_y = 0, bar_px = 0, bar_h = 0;
  std::string bar_label;
  int text_scale = 1, line_h = 0, swatch_px = 0;
  std::vector<Line> lines;  // caption, then the legend
};

std::string FormatMetres(double m) {
  return m >= 1 ? Printf("%g m", m) : Printf("%g cm", m * 100);
}

Layout MakeLayout(const TopView& view, const std::vector<VoxelLayer>& layers, const RenderOptions& options) {
  Layout l;
  const int s = options.text_scale, m = options.margin_px;
  l.text_scale = s;
  l.line_h = (kGlyphHeightPx + 4) * s;
  l.swatch_px = kGlyphHeightPx * s;
  l.map_x = m;
  l.map_y = m;
  const int map_bottom = m + view.map.height();

  const double bar_m = ScaleBarLengthM(view.x_max_m - view.x_min_m);
  l.bar_px = std::max(1, static_cast<int>(std::lround(bar_m / view.pixel_m)));
  l.bar_h = 2 * s + 2;
  l.bar_y = map_bottom + m;
  l.bar_label = FormatMetres(bar_m);
  int content_w = std::max(view.map.width(), l.bar_px + 3 * s + TextWidthPx(l.bar_label, s));

  int y = l.bar_y + std::max(l.bar_h, kGlyphHeightPx * s) + m / 2 + s;
  auto add = [&](std::string text, bool swatch, Rgb colour) {
    const int w = (swatch ? l.swatch_px + 3 * s : 0) + TextWidthPx(text, s);
    content_w = std::max(content_w, w);
    l.lines.push_back({y, std::move(text), swatch, colour});
    y += l.line_h;
  };
  add(Printf("top view, %.3g m/px, brighter = higher (z %.2f .. %.2f m)", view.pixel_m, view.z_min_m,
             view.z_max_m),
      false, kInk);
  for (const VoxelLayer& layer : layers) add(layer.label, true, layer.colour);
  if (layers.size() > 1) add("mixed colour: layers overlap", false, kInk);

  l.width = content_w + 2 * m;
  l.height = y + m;
  return l;
}

StatusOr<std::string> RenderPng(const TopView& view, const Layout& l, const RenderOptions& options) {
  RgbImage image(l.width, l.height, options.background);
  image.Blit(view.map, l.map_x, l.map_y);
  // A thin frame around the map area shows its extent even where it is empty.
  const Rgb frame{190, 190, 190};
  image.FillRect(l.map_x - 1, l.map_y - 1, view.map.width() + 2, 1, frame);
  image.FillRect(l.map_x - 1, l.map_y + view.map.height(), view.map.width() + 2, 1, frame);
  image.FillRect(l.map_x - 1, l.map_y - 1, 1, view.map.height() + 2, frame);
  image.FillRect(l.map_x + view.map.width(), l.map_y - 1, 1, view.map.height() + 2, frame);

  image.FillRect(l.map_x, l.bar_y, l.bar_px, l.bar_h, kInk);
  image.DrawText(l.map_x + l.bar_px + 3 * l.text_scale, l.bar_y, l.bar_label, l.text_scale, kInk);
  for (const Line& line : l.lines) {
    int x = l.map_x;
    if (line.swatch) {
      image.FillRect(x, line.y, l.swatch_px, l.swatch_px, line.colour);
      x += l.swatch_px + 3 * l.text_scale;
    }
    image.DrawText(x, line.y, line.text, l.text_scale, kInk);
  }
  return EncodePng(image);
}

std::string Hex(Rgb c) { return Printf("#%02x%02x%02x", c.r, c.g, c.b); }

std::string RenderSvg(const TopView& view, const std::string& map_png, const Layout& l,
                      const RenderOptions& options) {
  const int font_px = (kGlyphHeightPx + 2) * l.text_scale;
  std::string svg = Printf(
      "<svg xmlns=\"http://www.w3.org/2000/svg\" xmlns:xlink=\"http://www.w3.org/1999/xlink\" "
      "width=\"%d\" height=\"%d\" viewBox=\"0 0 %d %d\">\n"
      "<rect width=\"100%%\" height=\"100%%\" fill=\"%s\"/>\n",
      l.width, l.height, l.width, l.height, Hex(options.background).c_str());
  svg += Printf("<rect x=\"%d\" y=\"%d\" width=\"%d\" height=\"%d\" fill=\"none\" stroke=\"#bebebe\"/>\n",
                l.map_x, l.map_y, view.map.width(), view.map.height());
  svg += Printf("<image class=\"map\" x=\"%d\" y=\"%d\" width=\"%d\" height=\"%d\" "
                "style=\"image-rendering:pixelated\" xlink:href=\"data:image/png;base64,",
                l.map_x, l.map_y, view.map.width(), view.map.height());
  svg += Base64(map_png) + "\"/>\n";
  svg += Printf("<rect class=\"scale-bar\" x=\"%d\" y=\"%d\" width=\"%d\" height=\"%d\" fill=\"%s\"/>\n",
                l.map_x, l.bar_y, l.bar_px, l.bar_h, Hex(kInk).c_str());
  const char* text_style = "font-family=\"monospace\" dominant-baseline=\"hanging\"";
  svg += Printf("<text x=\"%d\" y=\"%d\" font-size=\"%d\" %s>%s</text>\n", l.map_x + l.bar_px + 3 * l.text_scale,
                l.bar_y, font_px, text_style, XmlEscape(l.bar_label).c_str());
  for (const Line& line : l.lines) {
    int x = l.map_x;
    if (line.swatch) {
      svg += Printf("<rect class=\"legend\" x=\"%d\" y=\"%d\" width=\"%d\" height=\"%d\" fill=\"%s\"/>\n", x,
                    line.y, l.swatch_px, l.swatch_px, Hex(line.colour).c_str());
      x += l.swatch_px + 3 * l.text_scale;
    }
    svg += Printf("<text x=\"%d\" y=\"%d\" font-size=\"%d\" %s>%s</text>\n", x, line.y, font_px, text_style,
                  XmlEscape(line.text).c_str());
  }
  svg += "</svg>\n";
  return svg;
}

}  // namespace

StatusOr<std::string> RenderVoxelImage(const std::vector<VoxelLayer>& layers, const RenderOptions& options,
                                       ImageFormat format) {
  StatusOr<TopView> view = RenderTopView(layers, options);
  if (!view.ok()) return view.status();
  const Layout layout = MakeLayout(*view, layers, options);
  if (format == ImageFormat::kPng) return RenderPng(*view, layout, options);
  StatusOr<std::string> map_png = EncodePng(view->map);
  if (!map_png.ok()) return map_png.status();
  return RenderSvg(*view, map_png.value(), layout, options);
}

}  // namespace mapd::client
