// Total-least-squares line fit from mergeable sufficient statistics
// (docs/algorithms.md A.7, "The fused line", Eq. 16-18).
//
// The statistics are kept centred (count, mean, scatter about the mean) rather
// than as raw sums: the raw form sum(p p^T) - sum(p) sum(p)^T / n cancels
// catastrophically for map coordinates of 1e5 m with centimetre spread. The
// centred form is the same information and still merges in O(1)
// (Chan, Golub & LeVeque, "Updating formulae ... for computing the sample variance").
#ifndef MAPD_GEOMETRY_LINE_FIT_H_
#define MAPD_GEOMETRY_LINE_FIT_H_

#include <Eigen/Core>
#include <cstdint>

#include "geometry/segment2.h"

namespace mapd::geometry {

// First and second moments of a 2D point set.
struct PointMoments2 {
  uint64_t count = 0;
  Vec2 mean = Vec2::Zero();                           // metres
  Eigen::Matrix2d scatter = Eigen::Matrix2d::Zero();  // sum of (p - mean)(p - mean)^T, m^2

  void Add(const Vec2& p);
  void Merge(const PointMoments2& other);
};

// An infinite line: point + t * direction.
struct Line2 {
  Vec2 point = Vec2::Zero();       // metres
  Vec2 direction = Vec2::UnitX();  // unit length, canonical sign (see CanonicalDirection)
};

// The orthogonal-regression line: through the centroid, along the principal
// direction of the scatter. Unlike y = a x + b it handles vertical walls.
// REQUIRES: m.count >= 1. An isotropic scatter (e.g. one point) yields an
// arbitrary but deterministic direction.
Line2 FitLine(const PointMoments2& m);

// The sign of a line direction is arbitrary; this picks the one with a positive
// component along a fixed reference direction (about 17 deg, chosen so that the
// flip falls on neither an axis nor a diagonal, where real walls are common).
// Makes a fused segment's a/b order independent of the order of the data.
Vec2 CanonicalDirection(const Vec2& unit_direction);

// The segment of `line` spanned by the extreme projections of `points` onto it.
// REQUIRES: points non-empty.
template <typename Range>
Segment2 ExtremeProjections(const Line2& line, const Range& points) {
  double t_min = 0.0;
  double t_max = 0.0;
  bool first = true;
  for (const Vec2& p : points) {
    const double t = (p - line.point).dot(line.direction);
    if (first || t < t_min) t_min = t;
    if (first || t > t_max) t_max = t;
    first = false;
  }
  return {line.point + t_min * line.direction, line.point + t_max * line.direction};
}

}  // namespace mapd::geometry

#endif  // MAPD_GEOMETRY_LINE_FIT_H_
