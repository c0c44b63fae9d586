#include "sim/scan_lines.h"

#include <cmath>

#include "geometry/line_fit.h"

namespace mapd::fusion::scenario {

using geometry::Segment2;
using geometry::Vec2;

namespace {

double ChordDistance(const Vec2& p, const Vec2& a, const Vec2& b) {
  const Vec2 u = b - a;
  const double n = u.norm();
  if (n == 0.0) return (p - a).norm();
  const Vec2 d = p - a;
  return std::abs(u.x() * d.y() - u.y() * d.x()) / n;
}

void Split(const std::vector<Vec2>& points, int first, int last, const ExtractionParams& params,
           std::vector<ExtractedLine>* out) {
  if (last - first + 1 < params.min_points) return;
  int worst = first;
  double worst_m = 0.0;
  for (int k = first + 1; k < last; ++k) {
    const double d = ChordDistance(points[static_cast<size_t>(k)], points[static_cast<size_t>(first)],
                                   points[static_cast<size_t>(last)]);
    if (d > worst_m) {
      worst_m = d;
      worst = k;
    }
  }
  if (worst_m > params.split_m) {
    Split(points, first, worst, params, out);
    Split(points, worst + 1, last, params, out);
    return;
  }
  geometry::PointMoments2 moments;
  for (int k = first; k <= last; ++k) moments.Add(points[static_cast<size_t>(k)]);
  const geometry::Line2 line = geometry::FitLine(moments);
  const auto project = [&](const Vec2& p) {
    return Vec2(line.point + (p - line.point).dot(line.direction) * line.direction);
  };
  const Segment2 s{project(points[static_cast<size_t>(first)]),
                   project(points[static_cast<size_t>(last)])};
  if (s.length() < params.min_length_m) return;
  out->push_back({s, first, last});
}

}  // namespace

std::vector<ExtractedLine> ExtractLines(const std::vector<Vec2>& points,
                                        const std::vector<bool>& valid, double beam_angle_rad,
                                        const ExtractionParams& params) {
  std::vector<ExtractedLine> out;
  const int n = static_cast<int>(points.size());
  int start = -1;
  for (int b = 0; b <= n; ++b) {
    bool continues = false;
    if (b < n && valid[static_cast<size_t>(b)] && start >= 0) {
      const Vec2& p = points[static_cast<size_t>(b)];
      const Vec2& q = points[static_cast<size_t>(b - 1)];
      const double limit = params.break_base_m + params.break_factor * p.norm() * beam_angle_rad;
      continues = (p - q).norm() <= limit;
    }
    if (continues) continue;
    if (start >= 0) Split(points, start, b - 1, params, &out);
    start = (b < n && valid[static_cast<size_t>(b)]) ? b : -1;
  }
  return out;
}

}  // namespace mapd::fusion::scenario
