#include "fusion/criteria.h"

#include <algorithm>
#include <cmath>

namespace mapd::fusion {

using geometry::Segment2;
using geometry::Vec2;

namespace {

double ClampedAcos(double x) { return std::acos(std::clamp(x, -1.0, 1.0)); }

// A total order on circles, so that OverlapRatio can put its arguments in a
// fixed order and be symmetric bit for bit.
bool CircleLess(const FeatureCircle& p, const FeatureCircle& q) {
  if (p.radius_m != q.radius_m) return p.radius_m < q.radius_m;
  if (p.centre.x() != q.centre.x()) return p.centre.x() < q.centre.x();
  return p.centre.y() < q.centre.y();
}

}  // namespace

double IncludedAngle(const Segment2& f, const Segment2& g) {
  const Vec2 u = f.direction();
  const Vec2 v = g.direction();
  // Eq. (5); the clamp absorbs rounding just above 1 for parallel segments.
  return ClampedAcos(std::abs(u.dot(v)) / (u.norm() * v.norm()));
}

FeatureCircle CircleOf(const Segment2& s) { return {s.midpoint(), 0.5 * s.length()}; }

double OverlapRatio(const FeatureCircle& f_in, const FeatureCircle& g_in) {
  const bool swap = CircleLess(g_in, f_in);
  const FeatureCircle& f = swap ? g_in : f_in;
  const FeatureCircle& g = swap ? f_in : g_in;
  const double rf = f.radius_m;
  const double rg = g.radius_m;
  const double d = (f.centre - g.centre).norm();
  if (d >= rf + rg) return 0.0;            // disjoint or externally tangent
  if (d <= std::abs(rf - rg)) return 1.0;  // one circle inside the other
  // Eq. (10): two circular sectors minus the kite M O_f N O_g.
  const double alpha_f = ClampedAcos((d * d + rf * rf - rg * rg) / (2.0 * d * rf));
  const double alpha_g = ClampedAcos((d * d + rg * rg - rf * rf) / (2.0 * d * rg));
  const double lens = alpha_f * rf * rf + alpha_g * rg * rg - d * rf * std::sin(alpha_f);
  const double r_min = std::min(rf, rg);
  // Eq. (9); rounding can leave the ratio a hair outside [0, 1].
  return std::clamp(lens / (M_PI * r_min * r_min), 0.0, 1.0);
}

double MaxCentreDistance(const Segment2& f, const Segment2& g) {
  return std::max(geometry::PointSegmentDistance(f.midpoint(), g),
                  geometry::PointSegmentDistance(g.midpoint(), f));
}

bool MeetsAllCriteria(const Segment2& f, const Segment2& g, const FusionParams& params) {
  // Cheapest first; the result is the conjunction either way.
  if (MaxCentreDistance(f, g) > params.eta_m) return false;
  if (IncludedAngle(f, g) > params.delta_rad) return false;
  return OverlapRatio(CircleOf(f), CircleOf(g)) >= params.gamma;
}

}  // namespace mapd::fusion
