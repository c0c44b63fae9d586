// FormatSvg: the fused map as an SVG drawing, drawn by cairo on an SVG
// surface. The drawing coordinates are metres with the y axis flipped
// (drawing y = -map y), so the picture has y up and text stays upright; one
// scale maps them to pixels. All lengths below are metres unless they say px.
#include "client/format_svg.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "client/cairo_canvas.h"
#include "client/text_util.h"

namespace mapd::client {
namespace {

namespace pb = mapserver::v1;

struct Box {
  double xmin, ymin, xmax, ymax;
};

Box Bounds(const FeatureList& features, const PlaneList& planes) {
  if (features.empty() && planes.empty()) return {0, 0, 10, 10};
  constexpr double kInf = std::numeric_limits<double>::infinity();
  Box b{kInf, kInf, -kInf, -kInf};
  const auto take = [&b](double x, double y) {
    if (!std::isfinite(x) || !std::isfinite(y)) return;
    b.xmin = std::min(b.xmin, x);
    b.ymin = std::min(b.ymin, y);
    b.xmax = std::max(b.xmax, x);
    b.ymax = std::max(b.ymax, y);
  };
  for (const pb::FusedFeature& f : features) {
    for (const pb::Vec2& p : {f.a(), f.b()}) take(p.x(), p.y());
  }
  for (const pb::FusedPlane& p : planes) {
    for (const pb::Vec3& v : p.boundary()) take(v.x(), v.y());
  }
  if (!(b.xmin <= b.xmax)) return {0, 0, 10, 10};  // no finite endpoint at all
  // A map of one straight wall still needs some area.
  if (b.xmax - b.xmin < 1) b.xmin -= 0.5, b.xmax += 0.5;
  if (b.ymax - b.ymin < 1) b.ymin -= 0.5, b.ymax += 0.5;
  return b;
}

// 1, 2 or 5 times a power of ten, so that `extent` holds at most ~30 steps.
double NiceStep(double extent) {
  double step = std::pow(10.0, std::floor(std::log10(std::max(extent, 1e-3) / 30)));
  for (double m : {1.0, 2.0, 5.0, 10.0}) {
    if (extent / (step * m) <= 30) return step * m;
  }
  return step * 10;
}

const char* KindColour(pb::FeatureKind kind) {
  switch (kind) {
    case pb::FEATURE_KIND_LINE:
      return "#1f77b4";
    case pb::FEATURE_KIND_PLANE:
      return "#d62728";
    default:
      return "#7f7f7f";
  }
}

constexpr char kPlaneColour[] = "#2ca02c";
constexpr char kGridColour[] = "#e0e0e0";
constexpr char kAxesColour[] = "#a0a0a0";

}  // namespace

std::string FormatSvg(const FeatureList& features, const SvgOptions& options) {
  return FormatSvg(features, {}, options);
}

std::string FormatSvg(const FeatureList& features, const PlaneList& planes,
                      const SvgOptions& options) {
  const Box data = Bounds(features, planes);
  const double extent = std::max(data.xmax - data.xmin, data.ymax - data.ymin);
  const double margin = std::max(0.5, 0.05 * extent);
  const double font = std::max(0.15, 0.025 * extent);
  const double band = 3.5 * font;  // below the map: scale bar and legend
  const double step = NiceStep(extent);
  const double base_width = std::max(0.02, 0.002 * extent);

  // The grid covers whole steps around the data.
  const double gx0 = std::floor((data.xmin - margin) / step) * step;
  const double gx1 = std::ceil((data.xmax + margin) / step) * step;
  const double gy0 = std::floor((data.ymin - margin) / step) * step;
  const double gy1 = std::ceil((data.ymax + margin) / step) * step;
  const double vx = gx0, vy = -gy1, vw = gx1 - gx0, vh = gy1 - gy0 + band;
  const double width_px = std::clamp(vw * options.pixels_per_metre, 400.0, 1600.0);
  const double height_px = width_px * vh / vw;

  Canvas canvas = Canvas::Svg(width_px, height_px);
  cairo_t* cr = canvas.cr();
  cairo_scale(cr, width_px / vw, width_px / vw);
  cairo_translate(cr, -vx, -vy);
  const auto stroke = [cr](const char* colour, double width, double alpha = 1.0) {
    SetColour(cr, ParseHexColour(colour), alpha);
    cairo_set_line_width(cr, width);
    cairo_stroke(cr);
  };
  const auto text = [cr, font](double x, double y, const std::string& s) {
    SetColour(cr, Rgb{0, 0, 0});
    cairo_set_font_size(cr, font);
    cairo_move_to(cr, x, y);
    cairo_show_text(cr, s.c_str());
  };
  cairo_select_font_face(cr, "sans-serif", CAIRO_FONT_SLANT_NORMAL, CAIRO_FONT_WEIGHT_NORMAL);
  SetColour(cr, Rgb{255, 255, 255});
  cairo_rectangle(cr, vx, vy, vw, vh);
  cairo_fill(cr);

  // Grid: one path, a line every step; the map axes darker.
  for (double x = gx0; x <= gx1 + 1e-9; x += step) {
    cairo_move_to(cr, x, -gy1);
    cairo_line_to(cr, x, -gy0);
  }
  for (double y = gy0; y <= gy1 + 1e-9; y += step) {
    cairo_move_to(cr, gx0, -y);
    cairo_line_to(cr, gx1, -y);
  }
  stroke(kGridColour, base_width * 0.5);
  if (gx0 <= 0 && 0 <= gx1 && gy0 <= 0 && 0 <= gy1) {
    cairo_move_to(cr, gx0, 0);
    cairo_line_to(cr, gx1, 0);
    cairo_move_to(cr, 0, -gy1);
    cairo_line_to(cr, 0, -gy0);
    stroke(kAxesColour, base_width * 0.7);
  }

  // Planes under the lines: translucent, so overlapping floor and ceiling both show.
  for (const pb::FusedPlane& p : planes) {
    if (p.boundary_size() == 0) continue;
    for (const pb::Vec3& v : p.boundary()) cairo_line_to(cr, v.x(), -v.y());
    cairo_close_path(cr);
    SetColour(cr, ParseHexColour(kPlaneColour), 0.15);
    cairo_fill_preserve(cr);
    stroke(kPlaneColour, base_width * 0.5, 0.5);
  }

  // Features, one stroke each: width grows with log2(support), capped at 4x.
  cairo_set_line_cap(cr, CAIRO_LINE_CAP_ROUND);
  for (const pb::FusedFeature& f : features) {
    const double w = base_width * std::min(4.0, 1.0 + std::log2(std::max(1u, f.support())) / 2);
    cairo_move_to(cr, f.a().x(), -f.a().y());
    cairo_line_to(cr, f.b().x(), -f.b().y());
    stroke(KindColour(f.kind()), w);
  }
  cairo_set_line_cap(cr, CAIRO_LINE_CAP_BUTT);

  // Scale bar (one grid step) and legend in the band under the map.
  const double by = -gy0 + 1.5 * font;
  const double bx = gx0 + font;
  cairo_move_to(cr, bx, by - 0.4 * font);
  cairo_rel_line_to(cr, 0, 0.4 * font);
  cairo_rel_line_to(cr, step, 0);
  cairo_rel_line_to(cr, 0, -0.4 * font);
  stroke("#000000", base_width);
  text(bx + step + 0.5 * font, by + 0.1 * font, Printf("%g m", step));
  double lx = bx + step + 4 * font;
  for (pb::FeatureKind kind : {pb::FEATURE_KIND_LINE, pb::FEATURE_KIND_PLANE}) {
    cairo_move_to(cr, lx, by);
    cairo_rel_line_to(cr, 1.5 * font, 0);
    stroke(KindColour(kind), base_width * 2);
    text(lx + 2 * font, by + 0.35 * font, KindName(kind));
    lx += 6 * font;
  }
  if (!planes.empty()) {
    SetColour(cr, ParseHexColour(kPlaneColour), 0.3);
    cairo_rectangle(cr, lx, by - 0.4 * font, 1.5 * font, 0.8 * font);
    cairo_fill(cr);
    text(lx + 2 * font, by + 0.35 * font, "floor/ceiling");
    lx += 9 * font;
  }
  text(lx, by + 0.35 * font, Printf("width ~ support; %zu features", features.size()));
  StatusOr<std::string> svg = canvas.FinishSvg();
  return svg.ok() ? std::move(svg.value()) : std::string();
}

}  // namespace mapd::client
