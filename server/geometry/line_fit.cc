#include "geometry/line_fit.h"

#include <cmath>

namespace mapd::geometry {

void PointMoments2::Add(const Vec2& p) {
  // Welford's update, written with the outer product so that the scatter stays
  // exactly symmetric.
  ++count;
  const Vec2 delta = p - mean;
  const double n = static_cast<double>(count);
  mean += delta / n;
  scatter += ((n - 1.0) / n) * (delta * delta.transpose());
}

void PointMoments2::Merge(const PointMoments2& other) {
  if (other.count == 0) return;
  if (count == 0) {
    *this = other;
    return;
  }
  const double na = static_cast<double>(count);
  const double nb = static_cast<double>(other.count);
  const double n = na + nb;
  const Vec2 delta = other.mean - mean;
  mean += delta * (nb / n);
  scatter += other.scatter + (na * nb / n) * (delta * delta.transpose());
  count += other.count;
}

Vec2 CanonicalDirection(const Vec2& unit_direction) {
  // cos/sin of 0.3 rad, the reference direction.
  static const Vec2 kReference(std::cos(0.3), std::sin(0.3));
  const double along = unit_direction.dot(kReference);
  if (along > 0.0) return unit_direction;
  if (along < 0.0) return -unit_direction;
  // Exactly perpendicular: use the perpendicular of the reference.
  const Vec2 normal(-kReference.y(), kReference.x());
  return unit_direction.dot(normal) >= 0.0 ? unit_direction : Vec2(-unit_direction);
}

Line2 FitLine(const PointMoments2& m) {
  const double sxx = m.scatter(0, 0);
  const double sxy = m.scatter(0, 1);
  const double syy = m.scatter(1, 1);
  // Principal axis of the symmetric 2x2 scatter: tan(2 theta) = 2 sxy / (sxx - syy).
  const double theta = 0.5 * std::atan2(2.0 * sxy, sxx - syy);
  Line2 line;
  line.point = m.mean;
  line.direction = CanonicalDirection(Vec2(std::cos(theta), std::sin(theta)));
  return line;
}

}  // namespace mapd::geometry
