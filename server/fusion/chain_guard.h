// The chain guard (docs/algorithms.md A.9, "The chain guard (curved
// walls)"). Clusters stay the connected components of the criteria graph;
// what is PUBLISHED is a deterministic function of each component's member set:
//
//   Groups(S), S a set of member features, P the 2|S| endpoints of S:
//   1. SSE(S) = sum of squared orthogonal distances of P to their total-least-
//      squares line (the smaller eigenvalue of the scatter of P, m^2);
//      RMS(S) = sqrt(SSE(S) / |P|).
//   2. If max_rms_m == 0 (guard off), |S| < 2 or RMS(S) <= max_rms_m: {S}.
//   3. Order S by the projection of each member's midpoint onto the fitted
//      direction (canonical sign, geometry::CanonicalDirection), ties by
//      ascending FeatureId. For k = 1 .. |S|-1, cost(k) = SSE(first k) +
//      SSE(the rest); k* = the smallest k of least cost.
//   4. The cuts k with cost(k) < max_sse_ratio * SSE(S), in ascending cost
//      (ties: smaller k); k* = the first the caller allows (the engine: both
//      sides reach min_support). None: {S} (the
//      misfit is noise spread along the line, not a bend, or a cut would
//      leave a piece that could not be published: it stays with the piece it
//      came from, so the guard never removes what the paper would publish).
//      Else Groups(first k*) and Groups(the rest).
// A curved wall chained into one component is thus cut into pieces that each
// fit a line within max_rms_m, while a straight wall with noise stays whole.
// Each group is named by its smallest FeatureId. Order independent: it depends
// on the member set alone.
#ifndef MAPD_FUSION_CHAIN_GUARD_H_
#define MAPD_FUSION_CHAIN_GUARD_H_

#include <cstdint>
#include <functional>
#include <vector>

#include "fusion/engine.h"
#include "geometry/line_fit.h"

namespace mapd::fusion {

// A member as the guard sees it. In bounded mode (engine.h) a member is a
// representative standing for every feature folded into it: `folded` then
// holds the moments of all their endpoints, which replace the two endpoints of
// `segment` in every SSE; the order key stays the midpoint of `segment`.
struct GuardMember {
  FeatureId id = 0;
  geometry::Segment2 segment;                       // map frame, metres
  const geometry::PointMoments2* folded = nullptr;  // null: just the segment's endpoints
};

// Sum of squared orthogonal distances to the TLS line: the smaller eigenvalue
// of m.scatter, m^2 (never negative).
double OrthogonalSse(const geometry::PointMoments2& m);

// Step 2's test on a whole component from its merged moments: true if the
// guard is on and RMS > max_rms_m, i.e. the member set must be examined.
bool ChainMayNeedSplit(const geometry::PointMoments2& endpoint_moments, double max_rms_m);

// Whether the caller allows cutting a subset into `head` and `tail` (indices
// into the members): the engine asks that both be publishable, wall
// consolidation that they be pieces along a line, not side by side.
using CutAllowed =
    std::function<bool(const std::vector<uint32_t>& head, const std::vector<uint32_t>& tail)>;

// Groups(members) as lists of indices into `members`, each ascending; the
// groups in order along the fitted direction. An empty `cut_allowed` allows
// every cut. REQUIRES: members non-empty.
std::vector<std::vector<uint32_t>> SplitChain(const std::vector<GuardMember>& members,
                                              double max_rms_m, double max_sse_ratio,
                                              const CutAllowed& cut_allowed = nullptr);

}  // namespace mapd::fusion

#endif  // MAPD_FUSION_CHAIN_GUARD_H_
