#include "fusion/plane_geometry.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>

#include "geometry/convex_hull2.h"

namespace mapd::fusion {
namespace {

using geometry::Cross;
using geometry::Segment2;
using geometry::Vec2;

// The polygon's edges; a point is one zero-length edge, a segment one edge.
std::vector<Segment2> Edges(const std::vector<Vec2>& p) {
  std::vector<Segment2> edges;
  if (p.size() == 1) edges.push_back({p[0], p[0]});
  if (p.size() == 2) edges.push_back({p[0], p[1]});
  if (p.size() >= 3) {
    for (size_t i = 0; i < p.size(); ++i) edges.push_back({p[i], p[(i + 1) % p.size()]});
  }
  return edges;
}

bool SegmentsCross(const Segment2& s, const Segment2& t) {
  const double d1 = Cross(t.a, t.b, s.a), d2 = Cross(t.a, t.b, s.b);
  const double d3 = Cross(s.a, s.b, t.a), d4 = Cross(s.a, s.b, t.b);
  return ((d1 > 0 && d2 < 0) || (d1 < 0 && d2 > 0)) && ((d3 > 0 && d4 < 0) || (d3 < 0 && d4 > 0));
}

bool InsideConvex(const std::vector<Vec2>& poly, const Vec2& p) {
  if (poly.size() < 3) return false;
  for (size_t i = 0; i < poly.size(); ++i) {
    if (Cross(poly[i], poly[(i + 1) % poly.size()], p) < 0) return false;
  }
  return true;
}

}  // namespace

Eigen::Vector3d CanonicalNormal(const Eigen::Vector3d& n) {
  // A tolerance well below any real tilt, so that rounding does not flip a
  // floor's normal; exactly vertical planes fall through to y, then x.
  constexpr double kEps = 1e-12;
  if (std::abs(n.z()) > kEps) return n.z() > 0 ? n : Eigen::Vector3d(-n);
  if (std::abs(n.y()) > kEps) return n.y() > 0 ? n : Eigen::Vector3d(-n);
  return n.x() >= 0 ? n : Eigen::Vector3d(-n);
}

double NormalAngle(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return std::acos(std::min(1.0, std::abs(a.dot(b))));
}

PlaneBasis PlaneBasis::Of(const Eigen::Vector3d& n) {
  // Seed with the axis least aligned with n: well conditioned for any n.
  const Eigen::Vector3d a = n.cwiseAbs();
  Eigen::Vector3d seed = Eigen::Vector3d::UnitX();
  if (a.y() <= a.x() && a.y() <= a.z()) seed = Eigen::Vector3d::UnitY();
  if (a.z() < a.x() && a.z() < a.y()) seed = Eigen::Vector3d::UnitZ();
  PlaneBasis b;
  b.u = (seed - n * n.dot(seed)).normalized();
  b.v = n.cross(b.u);
  return b;
}

std::vector<Vec2> ProjectedHull(const std::vector<Eigen::Vector3d>& points,
                                const PlaneBasis& basis) {
  std::vector<Vec2> p;
  p.reserve(points.size());
  for (const Eigen::Vector3d& x : points) p.push_back(basis.Project(x));
  return geometry::ConvexHull(std::move(p));
}

double PolygonArea(const std::vector<Vec2>& polygon) {
  double twice = 0;
  for (size_t i = 0; i < polygon.size(); ++i) {
    const Vec2& a = polygon[i];
    const Vec2& b = polygon[(i + 1) % polygon.size()];
    twice += a.x() * b.y() - a.y() * b.x();
  }
  return 0.5 * twice;
}

double ConvexIntersectionArea(const std::vector<Vec2>& a, const std::vector<Vec2>& b) {
  if (a.size() < 3 || b.size() < 3) return 0.0;
  std::vector<Vec2> out = a, in;
  for (size_t i = 0; i < b.size() && !out.empty(); ++i) {
    const Vec2& e0 = b[i];
    const Vec2& e1 = b[(i + 1) % b.size()];
    in.swap(out);
    out.clear();
    for (size_t j = 0; j < in.size(); ++j) {
      const Vec2& p = in[j];
      const Vec2& q = in[(j + 1) % in.size()];
      const double dp = Cross(e0, e1, p), dq = Cross(e0, e1, q);
      if (dp >= 0) out.push_back(p);
      if ((dp >= 0) != (dq >= 0)) out.push_back(p + (q - p) * (dp / (dp - dq)));
    }
  }
  return out.size() < 3 ? 0.0 : std::max(0.0, PolygonArea(out));
}

double ConvexPolygonGap(const std::vector<Vec2>& a, const std::vector<Vec2>& b) {
  if (a.empty() || b.empty()) return HUGE_VAL;
  if (InsideConvex(b, a[0]) || InsideConvex(a, b[0])) return 0.0;
  const std::vector<Segment2> ea = Edges(a), eb = Edges(b);
  for (const Segment2& s : ea) {
    for (const Segment2& t : eb) {
      if (SegmentsCross(s, t)) return 0.0;
    }
  }
  // Disjoint convex sets: the closest pair involves a vertex of one.
  double best = HUGE_VAL;
  for (const Vec2& p : a) {
    for (const Segment2& t : eb) best = std::min(best, geometry::PointSegmentDistance(p, t));
  }
  for (const Vec2& p : b) {
    for (const Segment2& s : ea) best = std::min(best, geometry::PointSegmentDistance(p, s));
  }
  return best;
}

bool NearConvexPolygon(const std::vector<Vec2>& polygon, const Vec2& p, double margin_m) {
  if (InsideConvex(polygon, p)) return true;
  for (const Segment2& e : Edges(polygon)) {
    if (geometry::PointSegmentDistance(p, e) <= margin_m) return true;
  }
  return false;
}

}  // namespace mapd::fusion
