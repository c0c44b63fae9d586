#include "eval/svg.h"

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <sstream>

namespace mapd::fusion::scenario {

using geometry::Segment2;
using geometry::Vec2;

Status WriteSvg(const std::string& path, const World& world, const std::vector<SvgPanel>& panels,
                const Vec2& lo, const Vec2& hi, double px_per_m) {
  const double w = (hi.x() - lo.x()) * px_per_m, h = (hi.y() - lo.y()) * px_per_m;
  constexpr double kTitle = 24.0, kGap = 10.0;
  std::ostringstream svg;
  const double total_w = panels.size() * (w + kGap);
  svg << "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" << total_w << "\" height=\""
      << h + kTitle << "\" font-family=\"sans-serif\" font-size=\"14\">\n";
  char buf[256];
  const auto outside = [&](const Segment2& s) {
    return std::max(s.a.x(), s.b.x()) < lo.x() || std::min(s.a.x(), s.b.x()) > hi.x() ||
           std::max(s.a.y(), s.b.y()) < lo.y() || std::min(s.a.y(), s.b.y()) > hi.y();
  };
  const auto line = [&](double ox, const Segment2& s, const char* style) {
    if (outside(s)) return;
    const auto X = [&](const Vec2& p) { return ox + (p.x() - lo.x()) * px_per_m; };
    const auto Y = [&](const Vec2& p) { return kTitle + (hi.y() - p.y()) * px_per_m; };
    std::snprintf(buf, sizeof(buf), "<line x1=\"%.2f\" y1=\"%.2f\" x2=\"%.2f\" y2=\"%.2f\" %s/>\n",
                  X(s.a), Y(s.a), X(s.b), Y(s.b), style);
    svg << buf;
  };
  for (size_t k = 0; k < panels.size(); ++k) {
    const double ox = k * (w + kGap);
    svg << "<rect x=\"" << ox << "\" y=\"" << kTitle << "\" width=\"" << w << "\" height=\"" << h
        << "\" fill=\"white\" stroke=\"#888\"/>\n";
    svg << "<text x=\"" << ox + 4 << "\" y=\"17\">" << panels[k].title << "</text>\n";
    svg << "<clipPath id=\"panel" << k << "\"><rect x=\"" << ox << "\" y=\"" << kTitle
        << "\" width=\"" << w << "\" height=\"" << h << "\"/></clipPath>\n<g clip-path=\"url(#panel"
        << k << ")\">\n";
    for (const Segment2& s : panels[k].raw) line(ox, s, "stroke=\"#f4b183\" stroke-width=\"0.5\"");
    for (size_t i = 0; i < world.structures.size(); ++i) {
      const bool wall = world.structures[i].kind == StructureKind::kWall;
      line(ox, world.structures[i].segment,
           wall ? "stroke=\"#bbb\" stroke-width=\"5\"" : "stroke=\"#ddd\" stroke-width=\"3\"");
    }
    for (const Segment2& s : panels[k].segments) {
      line(ox, s, "stroke=\"#1f4e9c\" stroke-width=\"1.5\"");
      if (outside(s)) continue;
      for (const Vec2& p : {s.a, s.b}) {
        std::snprintf(buf, sizeof(buf), "<circle cx=\"%.2f\" cy=\"%.2f\" r=\"2\" fill=\"#c00\"/>\n",
                      ox + (p.x() - lo.x()) * px_per_m, kTitle + (hi.y() - p.y()) * px_per_m);
        svg << buf;
      }
    }
    svg << "</g>\n";
  }
  svg << "</svg>\n";
  std::ofstream out(path);
  if (!out) return Status::Internal("cannot write " + path);
  out << svg.str();
  if (!out) return Status::Internal("write failed: " + path);
  return Status::Ok();
}

}  // namespace mapd::fusion::scenario
