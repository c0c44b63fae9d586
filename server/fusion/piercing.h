// Piercing (wall_consolidation.h): an observed-free cell on a piece's fitted
// segment, the last kPierceTrimM at each end aside, makes the piece join no
// other. The segment is sampled every kSampleStepM (half a free-space cell,
// so every cell it crosses is sampled).
//
// A refit moves a piece by millimetres on most observations, and sampling a
// long piece afresh each time was 12 % of the CPU guard's instructions. So a
// check also says how far each sample lies from the nearest observed-free
// cell (its clearance, at most kPierceClearanceCapM): while the samples of
// the refitted segment lie within that of the checked ones
// (SampleShiftBound), none is in a cell that was free at the check. Cells
// freed since are the consolidator's to catch: it rechecks every piece whose
// samples they come within kPierceClearanceCapM of (TakeEvidence).
#ifndef MAPD_FUSION_PIERCING_H_
#define MAPD_FUSION_PIERCING_H_

#include <algorithm>
#include <cmath>

#include "fusion/free_space.h"
#include "geometry/segment2.h"

namespace mapd::fusion {

// Piercing ignores this much of each end of a piece: its fitted end may
// overshoot the wall's corner, past which the space is free.
constexpr double kPierceTrimM = 0.5;
// Evidence is sampled along lines at this step: every cell a line crosses.
constexpr double kSampleStepM = 0.5 * FreeSpaceGrid::kCellM;
// The largest clearance a check reports: a tenth of a cell, so that only a
// sample's own cell and its eight neighbours matter.
constexpr double kPierceClearanceCapM = 0.02;

// The samples from p + t0 u to p + t1 u (both included): their count less
// one, and sample i of them. Every caller samples through these, so that a
// sample is the same point to the last bit wherever it is taken.
inline int SampleSteps(double t0, double t1) {
  return std::max(1, static_cast<int>(std::ceil((t1 - t0) / kSampleStepM)));
}
inline geometry::Vec2 SampleAt(const geometry::Vec2& p, const geometry::Vec2& u, double t0,
                               double t1, int i, int steps) {
  return p + (t0 + (t1 - t0) * static_cast<double>(i) / steps) * u;
}

struct PierceCheck {
  bool pierced = false;
  // Not pierced: no sample lies within this distance of a cell observed free
  // at the check (metres, in [0, kPierceClearanceCapM]).
  double clearance_m = 0.0;
};

// Whether an observed-free cell lies on `s` (its ends trimmed), and if not,
// its samples' clearance. A segment of at most 2 kPierceTrimM is never pierced
// and has no samples (clearance kPierceClearanceCapM).
PierceCheck CheckPiercing(const geometry::Segment2& s, const FreeSpaceGrid& free_space);
inline bool Pierced(const geometry::Segment2& s, const FreeSpaceGrid& free_space) {
  return CheckPiercing(s, free_space).pierced;
}

// An upper bound on how far any piercing sample of `from` lies from the
// sample of the same number of `to` (metres), or infinity when their samples
// do not correspond (different counts, or either one too short to sample).
double SampleShiftBound(const geometry::Segment2& from, const geometry::Segment2& to);

}  // namespace mapd::fusion

#endif  // MAPD_FUSION_PIERCING_H_
