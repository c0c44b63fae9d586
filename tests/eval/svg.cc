// WriteSvg, drawn by cairo on an SVG surface (client/cairo_canvas.h): one
// panel per map, each clipped to its window, y up.
#include "eval/svg.h"

#include <algorithm>
#include <cmath>
#include <fstream>

#include "client/cairo_canvas.h"

namespace mapd::fusion::scenario {

using geometry::Segment2;
using geometry::Vec2;

namespace {

constexpr double kTitlePx = 24.0, kGapPx = 10.0;

// How a segment is drawn: colour "#rrggbb", width in px.
struct Stroke {
  const char* hex;
  double width_px;
  double alpha = 1.0;
};

}  // namespace

Status WriteSvg(const std::string& path, const World& world, const std::vector<SvgPanel>& panels,
                const Vec2& lo, const Vec2& hi, double px_per_m) {
  const double w = (hi.x() - lo.x()) * px_per_m, h = (hi.y() - lo.y()) * px_per_m;
  client::Canvas canvas = client::Canvas::Svg(panels.size() * (w + kGapPx), h + kTitlePx);
  cairo_t* cr = canvas.cr();
  cairo_select_font_face(cr, "sans-serif", CAIRO_FONT_SLANT_NORMAL, CAIRO_FONT_WEIGHT_NORMAL);
  cairo_set_font_size(cr, 14.0);
  cairo_set_line_cap(cr, CAIRO_LINE_CAP_ROUND);

  const auto outside = [&](const Segment2& s) {
    return std::max(s.a.x(), s.b.x()) < lo.x() || std::min(s.a.x(), s.b.x()) > hi.x() ||
           std::max(s.a.y(), s.b.y()) < lo.y() || std::min(s.a.y(), s.b.y()) > hi.y();
  };
  for (std::size_t k = 0; k < panels.size(); ++k) {
    const double ox = k * (w + kGapPx);
    const auto X = [&](const Vec2& p) { return ox + (p.x() - lo.x()) * px_per_m; };
    const auto Y = [&](const Vec2& p) { return kTitlePx + (hi.y() - p.y()) * px_per_m; };
    const auto line = [&](const Segment2& s, const Stroke& stroke) {
      if (outside(s)) return;
      client::SetColour(cr, client::ParseHexColour(stroke.hex), stroke.alpha);
      cairo_set_line_width(cr, stroke.width_px);
      cairo_move_to(cr, X(s.a), Y(s.a));
      cairo_line_to(cr, X(s.b), Y(s.b));
      cairo_stroke(cr);
    };

    cairo_set_source_rgb(cr, 0, 0, 0);
    cairo_move_to(cr, ox + 4, 17);
    cairo_show_text(cr, panels[k].title.c_str());
    cairo_rectangle(cr, ox, kTitlePx, w, h);
    cairo_set_source_rgb(cr, 1, 1, 1);
    cairo_fill_preserve(cr);
    client::SetColour(cr, client::ParseHexColour("#888888"));
    cairo_set_line_width(cr, 1.0);
    cairo_stroke(cr);

    cairo_save(cr);
    cairo_rectangle(cr, ox, kTitlePx, w, h);
    cairo_clip(cr);
    for (const Segment2& s : panels[k].raw) line(s, {"#f4b183", 0.5});
    for (const Structure& structure : world.structures) {
      const bool wall = structure.kind == StructureKind::kWall;
      line(structure.segment, wall ? Stroke{"#bbbbbb", 5.0} : Stroke{"#dddddd", 3.0});
    }
    for (const Segment2& s : panels[k].segments) {
      line(s, {"#1f4e9c", 1.5});
      if (outside(s)) continue;
      client::SetColour(cr, client::ParseHexColour("#cc0000"));
      for (const Vec2& p : {s.a, s.b}) {
        cairo_new_sub_path(cr);
        cairo_arc(cr, X(p), Y(p), 2.0, 0.0, 2 * M_PI);
      }
      cairo_fill(cr);
    }
    cairo_restore(cr);
  }
  auto svg = canvas.FinishSvg();
  if (!svg.ok()) return svg.status();
  std::ofstream out(path, std::ios::binary);
  if (!out) return Status::Internal("cannot write " + path);
  out << *svg;
  if (!out) return Status::Internal("write failed: " + path);
  return Status::Ok();
}

}  // namespace mapd::fusion::scenario
