// FormatSvg: the fused map as an SVG drawing. The viewBox is in metres with
// the y axis flipped (SVG y = -map y), so the picture has y up and text stays
// upright; all lengths below are metres unless they say px.
#include <algorithm>
#include <cmath>
#include <limits>

#include "client/format.h"
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
    case pb::FEATURE_KIND_LINE: return "#1f77b4";
    case pb::FEATURE_KIND_PLANE: return "#d62728";
    default: return "#7f7f7f";
  }
}

constexpr char kPlaneColour[] = "#2ca02c";

}  // namespace

std::string FormatSvg(const FeatureList& features, const SvgOptions& options) {
  return FormatSvg(features, {}, options);
}

std::string FormatSvg(const FeatureList& features, const PlaneList& planes, const SvgOptions& options) {
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

  std::string out = Printf(
      "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n"
      "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"%.0f\" height=\"%.0f\" viewBox=\"%.3f %.3f %.3f %.3f\">\n"
      "<title>%s</title>\n"
      "<desc>Map frame, metres; y axis up. %zu features. Grid step %g m.</desc>\n"
      "<rect x=\"%.3f\" y=\"%.3f\" width=\"%.3f\" height=\"%.3f\" fill=\"white\"/>\n",
      width_px, height_px, vx, vy, vw, vh, XmlEscape(options.title).c_str(), features.size(), step, vx, vy, vw, vh);

  // Grid: one path, a line every step; the map axes darker.
  std::string grid;
  for (double x = gx0; x <= gx1 + 1e-9; x += step) grid += Printf("M%.3f %.3fV%.3f", x, -gy1, -gy0);
  for (double y = gy0; y <= gy1 + 1e-9; y += step) grid += Printf("M%.3f %.3fH%.3f", gx0, -y, gx1);
  out += Printf("<path class=\"grid\" d=\"%s\" stroke=\"#e0e0e0\" stroke-width=\"%.4f\" fill=\"none\"/>\n",
                grid.c_str(), base_width * 0.5);
  if (gx0 <= 0 && 0 <= gx1 && gy0 <= 0 && 0 <= gy1) {
    out += Printf("<path class=\"axes\" d=\"M%.3f 0H%.3fM0 %.3fV%.3f\" stroke=\"#a0a0a0\" stroke-width=\"%.4f\"/>\n",
                  gx0, gx1, -gy1, -gy0, base_width * 0.7);
  }

  // Planes under the lines: translucent, so overlapping floor and ceiling both show.
  if (!planes.empty()) {
    out += "<g class=\"planes\">\n";
    for (const pb::FusedPlane& p : planes) {
      std::string points;
      for (const pb::Vec3& v : p.boundary()) points += Printf("%s%.3f,%.3f", points.empty() ? "" : " ", v.x(), -v.y());
      std::string robots;
      for (const std::string& r : p.robots()) robots += (robots.empty() ? "" : ",") + r;
      out += Printf(
          "<polygon class=\"plane\" points=\"%s\" fill=\"%s\" fill-opacity=\"0.15\" stroke=\"%s\" "
          "stroke-opacity=\"0.5\" stroke-width=\"%.4f\"><title>plane #%llu, z %.2f..%.2f m, %.1f m2, support %u, "
          "robots %s</title></polygon>\n",
          points.c_str(), kPlaneColour, kPlaneColour, base_width * 0.5, static_cast<unsigned long long>(p.id()),
          p.z_min(), p.z_max(), p.area(), p.support(), XmlEscape(robots).c_str());
    }
    out += "</g>\n";
  }

  // Features: width grows with log2(support), capped at 4x.
  out += "<g class=\"features\" stroke-linecap=\"round\">\n";
  for (const pb::FusedFeature& f : features) {
    const double w = base_width * std::min(4.0, 1.0 + std::log2(std::max(1u, f.support())) / 2);
    std::string robots;
    for (const std::string& r : f.robots()) robots += (robots.empty() ? "" : ",") + r;
    out += Printf(
        "<line class=\"feature %s\" x1=\"%.3f\" y1=\"%.3f\" x2=\"%.3f\" y2=\"%.3f\" stroke=\"%s\" "
        "stroke-width=\"%.4f\"><title>#%llu %s, support %u, %u members, robots %s</title></line>\n",
        KindName(f.kind()).c_str(), f.a().x(), -f.a().y(), f.b().x(), -f.b().y(), KindColour(f.kind()), w,
        static_cast<unsigned long long>(f.id()), KindName(f.kind()).c_str(), f.support(), f.member_count(),
        XmlEscape(robots).c_str());
  }
  out += "</g>\n";

  // Scale bar (one grid step) and legend in the band under the map.
  const double by = -gy0 + 1.5 * font;
  const double bx = gx0 + font;
  out += Printf("<g class=\"scalebar\"><path d=\"M%.3f %.3fv%.3fh%.3fv%.3f\" stroke=\"black\" "
                "stroke-width=\"%.4f\" fill=\"none\"/><text x=\"%.3f\" y=\"%.3f\" font-size=\"%.3f\" "
                "font-family=\"sans-serif\">%g m</text></g>\n",
                bx, by - 0.4 * font, 0.4 * font, step, -0.4 * font, base_width, bx + step + 0.5 * font,
                by + 0.1 * font, font, step);
  double lx = bx + step + 4 * font;
  out += "<g class=\"legend\" font-family=\"sans-serif\">\n";
  for (pb::FeatureKind kind : {pb::FEATURE_KIND_LINE, pb::FEATURE_KIND_PLANE}) {
    out += Printf("<path d=\"M%.3f %.3fh%.3f\" stroke=\"%s\" stroke-width=\"%.4f\"/>"
                  "<text x=\"%.3f\" y=\"%.3f\" font-size=\"%.3f\">%s</text>\n",
                  lx, by, 1.5 * font, KindColour(kind), base_width * 2, lx + 2 * font, by + 0.35 * font, font,
                  KindName(kind).c_str());
    lx += 6 * font;
  }
  if (!planes.empty()) {
    out += Printf("<rect x=\"%.3f\" y=\"%.3f\" width=\"%.3f\" height=\"%.3f\" fill=\"%s\" fill-opacity=\"0.3\"/>"
                  "<text x=\"%.3f\" y=\"%.3f\" font-size=\"%.3f\">floor/ceiling</text>\n",
                  lx, by - 0.4 * font, 1.5 * font, 0.8 * font, kPlaneColour, lx + 2 * font, by + 0.35 * font, font);
    lx += 9 * font;
  }
  out += Printf("<text x=\"%.3f\" y=\"%.3f\" font-size=\"%.3f\">width ~ support; %zu features</text>\n", lx,
                by + 0.35 * font, font, features.size());
  out += "</g>\n</svg>\n";
  return out;
}

}  // namespace mapd::client
