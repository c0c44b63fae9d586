// Proof of occlusion for wall consolidation (docs/algorithms.md A.11).
//
// Visibility triangles (free_space.h) mark where rays reached an observed
// segment. A stretch of a wall line that no triangle crossed is either
// occluded (something stood in front of it) or seen through to something
// that left no segment: clutter behind a doorway, too sparse for a line, or
// nothing within range. Indoors the second is common, and joining two pieces
// of a wall across such a gap closes a doorway the robot looked through.
//
// One observation can tell the two apart. If it holds two pieces of one wall
// line with a gap between them and another of its segments lies in front of
// the line within the gap's wedge, that segment hid the part of the gap
// behind it: the gap there is occluded, proven. OccludedStretches returns
// those parts (the occluder's shadow on the line, clipped to the gap).
// Consolidation joins gaps up to FusionParams::wall_proof_gap_m only where
// every part was proven occluded (and none was seen free).
//
// Pairs are taken among segments at most kProofPairWindow apart in the
// order of their midpoints' bearings from the sensor, so the work is
// O(n * kProofPairWindow * n) for n segments in the worst case and linear
// when few pairs are collinear (the collinearity test comes first).
#ifndef MAPD_FUSION_OCCLUSION_PROOF_H_
#define MAPD_FUSION_OCCLUSION_PROOF_H_

#include <vector>

#include "fusion/params.h"
#include "geometry/segment2.h"

namespace mapd::fusion {

inline constexpr int kProofPairWindow = 4;

// The stretches of wall line, map frame, that `segments` (one observation,
// seen from `origin`) prove occluded: for every pair p, q within the window
// that lie on one line (the longer one's, L: included angle <= delta_rad, the
// shorter's endpoints within wall_offset_m of L's line) with a gap along L of
// more than wall_gap_m and at most wall_occluded_gap_m, seen from the front
// (the sensor more than wall_offset_m off the line), each other segment that
// lies between the sensor and the line (offset by wall_offset_m towards the
// sensor) within the wedge contributes its shadow on L's line, clipped to the
// gap.
std::vector<geometry::Segment2> OccludedStretches(const geometry::Vec2& origin,
                                                  const std::vector<geometry::Segment2>& segments,
                                                  const FusionParams& params);

}  // namespace mapd::fusion

#endif  // MAPD_FUSION_OCCLUSION_PROOF_H_
