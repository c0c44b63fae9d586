// The three fusion criteria of the feature-fusion paper (Li et al. 2023)
// section 3.1, as pure functions (docs/algorithms.md A.2, "The three
// criteria"; its Eq. 5-13 are the paper's eqs. (5)-(13) cited below).
//
// Every function is symmetric in its two features, bit for bit: the engine
// evaluates (new, old) pairs while a batch evaluates (i, j) with i < j, and both
// must take the same decision on a borderline pair.
#ifndef MAPD_FUSION_CRITERIA_H_
#define MAPD_FUSION_CRITERIA_H_

#include "fusion/params.h"
#include "geometry/segment2.h"

namespace mapd::fusion {

// Criterion 1, paper eq. (5): beta = acos(|u.v| / (|u||v|)), radians in [0, pi/2].
// REQUIRES: both segments have non-zero length.
double IncludedAngle(const geometry::Segment2& f, const geometry::Segment2& g);

// Paper eqs. (7)-(8): centre = midpoint, radius = half the length.
struct FeatureCircle {
  geometry::Vec2 centre = geometry::Vec2::Zero();  // metres
  double radius_m = 0.0;
};
FeatureCircle CircleOf(const geometry::Segment2& s);

// Criterion 2, paper eqs. (9)-(10): lens area / area of the smaller circle, in [0, 1].
// 0 if D >= R_f + R_g (tangent circles included), 1 if D <= |R_f - R_g|.
double OverlapRatio(const FeatureCircle& f, const FeatureCircle& g);

// Criterion 3, paper eq. (12): max(dist(O_f, segment g), dist(O_g, segment f)),
// point-to-SEGMENT distances, metres.
double MaxCentreDistance(const geometry::Segment2& f, const geometry::Segment2& g);

// beta <= delta (eq. 6), eps >= gamma (eq. 11), d_max <= eta (eq. 13).
// Whether f and g come from different observations is the caller's business.
bool MeetsAllCriteria(const geometry::Segment2& f, const geometry::Segment2& g,
                      const FusionParams& params);

}  // namespace mapd::fusion

#endif  // MAPD_FUSION_CRITERIA_H_
