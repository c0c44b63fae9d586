#include "eval/metrics.h"

#include <algorithm>
#include <cmath>
#include <set>
#include <utility>

namespace mapd::fusion::scenario {

using geometry::Segment2;
using geometry::Vec2;

namespace {

double LineDistance(const Vec2& p, const Segment2& s) {
  const Vec2 u = s.direction().normalized();
  const Vec2 d = p - s.a;
  return std::abs(u.x() * d.y() - u.y() * d.x());
}

// [lo, hi] of s projected onto wall w, in metres from w.a along w.
std::pair<double, double> Interval(const Segment2& s, const Segment2& w) {
  const Vec2 u = w.direction().normalized();
  const double a = (s.a - w.a).dot(u), b = (s.b - w.a).dot(u);
  return {std::min(a, b), std::max(a, b)};
}

// Length of the union of intervals, clipped to [lo, hi].
double UnionLength(std::vector<std::pair<double, double>> v, double lo, double hi) {
  std::sort(v.begin(), v.end());
  double total = 0.0, cur_lo = 0.0, cur_hi = 0.0;
  bool open = false;
  for (auto [a, b] : v) {
    a = std::max(a, lo);
    b = std::min(b, hi);
    if (b <= a) continue;
    if (open && a <= cur_hi) {
      cur_hi = std::max(cur_hi, b);
      continue;
    }
    if (open) total += cur_hi - cur_lo;
    cur_lo = a;
    cur_hi = b;
    open = true;
  }
  if (open) total += cur_hi - cur_lo;
  return total;
}

}  // namespace

int MatchStructure(const World& world, const Segment2& s, const MetricsParams& params) {
  if (s.length() == 0.0) return -1;
  const Vec2 su = s.direction().normalized();
  int best = -1;
  double best_m = 0.0;
  for (size_t k = 0; k < world.structures.size(); ++k) {
    const Segment2& w = world.structures[k].segment;
    const double d = geometry::PointSegmentDistance(s.midpoint(), w);
    if (d > params.match_m + 0.5 * s.length()) continue;
    if (std::abs(su.dot(w.direction().normalized())) < std::cos(params.max_angle_rad)) continue;
    if (LineDistance(s.a, w) > params.match_m || LineDistance(s.b, w) > params.match_m) continue;
    const auto [lo, hi] = Interval(s, w);
    if (hi <= 0.0 || lo >= w.length()) continue;
    if (best < 0 || d < best_m) {
      best = static_cast<int>(k);
      best_m = d;
    }
  }
  return best;
}

MapMetrics Evaluate(const World& world, const std::vector<Scan>& raw,
                    const std::vector<FusedFeature>& fused, const MetricsParams& params) {
  MapMetrics m;
  m.fused = fused.size();
  const size_t walls = world.wall_count;
  // What the scans saw of each wall.
  std::vector<std::set<ObservationId>> scans_on(walls);
  std::vector<std::vector<std::pair<double, double>>> seen_iv(walls);
  for (const Scan& scan : raw) {
    for (size_t k = 0; k < scan.features.size(); ++k) {
      const int t = scan.truth[k];
      if (t < 0 || static_cast<size_t>(t) >= walls) continue;
      scans_on[static_cast<size_t>(t)].insert(scan.observation);
      seen_iv[static_cast<size_t>(t)].push_back(
          Interval(scan.features[k].segment, world.structures[static_cast<size_t>(t)].segment));
    }
  }
  std::vector<bool> seen(walls, false);
  for (size_t w = 0; w < walls; ++w) {
    seen[w] = scans_on[w].size() >= params.min_scans;
    if (seen[w]) ++m.walls_seen;
  }
  // Match the fused features.
  std::vector<std::vector<const FusedFeature*>> on_wall(walls);
  double lateral_sum = 0.0;
  size_t lateral_n = 0;
  for (const FusedFeature& f : fused) {
    const int s = MatchStructure(world, f.segment, params);
    if (s < 0) {
      ++m.spurious;
    } else if (static_cast<size_t>(s) >= walls) {
      ++m.on_trivial;
    } else {
      ++m.on_walls;
      on_wall[static_cast<size_t>(s)].push_back(&f);
      const Segment2& w = world.structures[static_cast<size_t>(s)].segment;
      for (const Vec2& p : {f.segment.a, f.segment.b}) {
        lateral_sum += LineDistance(p, w) * LineDistance(p, w);
        ++lateral_n;
      }
    }
  }
  m.lateral_rms_m = lateral_n > 0 ? std::sqrt(lateral_sum / lateral_n) : 0.0;
  // Completeness over the seen walls: the observed extent covered by matches.
  double seen_len = 0.0, covered_len = 0.0;
  for (size_t w = 0; w < walls; ++w) {
    if (!on_wall[w].empty()) ++m.walls_matched;
    if (!seen[w]) continue;
    const Segment2& ws = world.structures[w].segment;
    const double observed = UnionLength(seen_iv[w], 0.0, ws.length());
    std::vector<std::pair<double, double>> cover;
    for (const FusedFeature* f : on_wall[w]) cover.push_back(Interval(f->segment, ws));
    // Covered AND observed: pairwise intersections, then their union.
    std::vector<std::pair<double, double>> both;
    for (const auto& c : cover) {
      for (const auto& o : seen_iv[w]) {
        const double a = std::max(c.first, o.first), b = std::min(c.second, o.second);
        if (b > a) both.push_back({a, b});
      }
    }
    seen_len += observed;
    covered_len += UnionLength(both, 0.0, ws.length());
  }
  m.completeness = seen_len > 0.0 ? covered_len / seen_len : 0.0;
  m.redundancy = m.walls_matched > 0 ? static_cast<double>(m.on_walls) / m.walls_matched : 0.0;
  // Vertex error (Table 2).
  const auto reaches = [&](int wall, const Vec2& corner) {
    const Segment2& ws = world.structures[static_cast<size_t>(wall)].segment;
    const double at = (corner - ws.a).dot(ws.direction().normalized());
    for (const auto& [lo, hi] : seen_iv[static_cast<size_t>(wall)]) {
      if (std::abs(lo - at) <= params.corner_reach_m ||
          std::abs(hi - at) <= params.corner_reach_m) {
        return true;
      }
    }
    return false;
  };
  for (size_t ci = 0; ci < world.corners.size(); ++ci) {
    const Corner& c = world.corners[ci];
    if (!seen[static_cast<size_t>(c.in)] || !seen[static_cast<size_t>(c.out)]) continue;
    if (!reaches(c.in, c.point) || !reaches(c.out, c.point)) continue;
    ++m.corners_evaluated;
    double sum = 0.0;
    bool met = true;
    for (int wall : {c.in, c.out}) {
      double best = params.corner_radius_m + 1.0;
      for (const FusedFeature* f : on_wall[static_cast<size_t>(wall)]) {
        best = std::min({best, (f->segment.a - c.point).norm(), (f->segment.b - c.point).norm()});
      }
      met = met && best <= params.corner_radius_m;
      sum += best;
    }
    if (!met) continue;
    ++m.corners_met;
    m.vertex_errors_m.push_back(sum);
    m.met_corners.push_back(ci);
  }
  if (!m.vertex_errors_m.empty()) {
    double total = 0.0;
    for (double e : m.vertex_errors_m) total += e;
    m.vertex_error_mean_m = total / m.vertex_errors_m.size();
    std::vector<double> sorted = m.vertex_errors_m;
    std::sort(sorted.begin(), sorted.end());
    const size_t n = sorted.size();
    m.vertex_error_median_m = n % 2 ? sorted[n / 2] : 0.5 * (sorted[n / 2 - 1] + sorted[n / 2]);
  }
  return m;
}

}  // namespace mapd::fusion::scenario
