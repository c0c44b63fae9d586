#include "fusion/occlusion_proof.h"

#include <algorithm>
#include <cmath>
#include <numeric>

namespace mapd::fusion {

using geometry::Cross;
using geometry::Segment2;
using geometry::Vec2;

namespace {

// Whether segment s has a point strictly inside the triangle (o, p, q).
bool CrossesTriangle(const Segment2& s, const Vec2& o, const Vec2& p, const Vec2& q) {
  const double orient = Cross(p - o, q - o);
  if (orient == 0.0) return false;
  const auto inside = [&](const Vec2& x) {
    const double a = Cross(p - o, x - o), b = Cross(q - p, x - p), c = Cross(o - q, x - q);
    return orient > 0.0 ? (a > 0.0 && b > 0.0 && c > 0.0) : (a < 0.0 && b < 0.0 && c < 0.0);
  };
  if (inside(s.a) || inside(s.b)) return true;
  const auto proper = [](const Vec2& a, const Vec2& b, const Vec2& c, const Vec2& d) {
    const double d1 = Cross(b - a, c - a), d2 = Cross(b - a, d - a);
    const double d3 = Cross(d - c, a - c), d4 = Cross(d - c, b - c);
    return d1 * d2 < 0.0 && d3 * d4 < 0.0;
  };
  return proper(s.a, s.b, o, p) || proper(s.a, s.b, p, q) || proper(s.a, s.b, q, o);
}

// Where the ray from o through x meets the line l.a + t u, as t; false if
// it never does going forward (parallel, or the line is behind o).
bool RayOnLine(const Vec2& o, const Vec2& x, const Vec2& la, const Vec2& u, double* t) {
  const Vec2 d = x - o;
  const double denom = Cross(u, d);
  if (std::abs(denom) < 1e-12) return false;
  const double s = Cross(u, la - o) / denom;  // o + s d lies on the line
  if (!(s > 0.0)) return false;
  *t = u.dot(o + s * d - la);
  return true;
}

}  // namespace

std::vector<Segment2> OccludedStretches(const Vec2& origin, const std::vector<Segment2>& segments,
                                        const FusionParams& params) {
  std::vector<Segment2> out;
  const size_t n = segments.size();
  if (n < 3) return out;  // two pieces and an occluder at least
  std::vector<double> bearing(n);
  for (size_t i = 0; i < n; ++i) {
    const Vec2 m = 0.5 * (segments[i].a + segments[i].b) - origin;
    bearing[i] = std::atan2(m.y(), m.x());
  }
  std::vector<size_t> order(n);
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(), [&](size_t x, size_t y) {
    return bearing[x] < bearing[y] || (bearing[x] == bearing[y] && x < y);
  });
  const double offset_m = params.wall_offset_m;
  for (size_t oi = 0; oi < n; ++oi) {
    for (size_t k = 1; k <= static_cast<size_t>(kProofPairWindow) && oi + k < n; ++k) {
      const size_t pi = order[oi], qi = order[oi + k];
      const Segment2& p = segments[pi];
      const Segment2& q = segments[qi];
      const double lp = p.length(), lq = q.length();
      const Segment2& l = lp >= lq ? p : q;
      const Segment2& s = lp >= lq ? q : p;
      const double l_length = std::max(lp, lq), s_length = std::min(lp, lq);
      if (!(s_length > 0.0)) continue;
      const Vec2 u = l.direction() / l_length;
      if (std::abs(Cross(u, s.direction() / s_length)) > std::sin(params.delta_rad)) continue;
      if (std::abs(Cross(u, s.a - l.a)) > offset_m || std::abs(Cross(u, s.b - l.a)) > offset_m) {
        continue;
      }
      const double ta = u.dot(s.a - l.a), tb = u.dot(s.b - l.a);
      double t0 = 0.0, t1 = 0.0;  // the gap along L's line
      if (std::min(ta, tb) > l_length) {
        t0 = l_length;
        t1 = std::min(ta, tb);
      } else if (std::max(ta, tb) < 0.0) {
        t0 = std::max(ta, tb);
        t1 = 0.0;
      } else {
        continue;  // they overlap: no gap
      }
      if (t1 - t0 <= params.wall_gap_m || t1 - t0 > params.wall_occluded_gap_m) continue;
      const double side = Cross(u, origin - l.a);  // the sensor's signed distance from the line
      if (std::abs(side) <= offset_m) continue;
      const Vec2 toward = (side > 0.0 ? offset_m : -offset_m) * Vec2(-u.y(), u.x());
      const Vec2 g0 = l.a + t0 * u + toward, g1 = l.a + t1 * u + toward;
      for (size_t j = 0; j < n; ++j) {
        if (j == pi || j == qi) continue;
        const Segment2& occluder = segments[j];
        if (!CrossesTriangle(occluder, origin, g0, g1)) continue;
        double ta_shadow = 0.0, tb_shadow = 0.0;
        if (!RayOnLine(origin, occluder.a, l.a, u, &ta_shadow) ||
            !RayOnLine(origin, occluder.b, l.a, u, &tb_shadow)) {
          continue;  // a shadow with no end on the line: prove nothing
        }
        const double lo = std::max(t0, std::min(ta_shadow, tb_shadow));
        const double hi = std::min(t1, std::max(ta_shadow, tb_shadow));
        if (hi > lo) out.push_back(Segment2{l.a + lo * u, l.a + hi * u});
      }
    }
  }
  return out;
}

}  // namespace mapd::fusion
