#include "fusion/piercing.h"

#include <limits>

namespace mapd::fusion {

using geometry::Segment2;
using geometry::Vec2;

namespace {

// Rounding in the samples' arithmetic (coordinates up to 1e6 m: an ulp is
// 1.2e-10 m) is far below this.
constexpr double kShiftSlackM = 1e-8;

}  // namespace

PierceCheck CheckPiercing(const Segment2& s, const FreeSpaceGrid& free_space) {
  PierceCheck check;
  check.clearance_m = kPierceClearanceCapM;
  const double length = s.length();
  if (!(length > 2.0 * kPierceTrimM)) return check;
  const Vec2 u = s.direction() / length;
  const double t0 = kPierceTrimM, t1 = length - kPierceTrimM;
  const int steps = SampleSteps(t0, t1);
  constexpr double kCell = FreeSpaceGrid::kCellM;
  constexpr double kCap = kPierceClearanceCapM;
  FreeSpaceGrid::Probe probe(free_space);
  FreeSpaceGrid::Probe neighbours(free_space);  // keeps its own tile
  // Whether the cell (cx + dx, cy + dy) is free, through its centre.
  const auto free_at = [&](int64_t cx, int64_t cy, int dx, int dy) {
    return neighbours.IsFree(Vec2((static_cast<double>(cx + dx) + 0.5) * kCell,
                                  (static_cast<double>(cy + dy) + 0.5) * kCell));
  };
  for (int i = 0; i <= steps; ++i) {
    const Vec2 x = SampleAt(s.a, u, t0, t1, i, steps);
    if (probe.IsFree(x)) {
      check.pierced = true;
      check.clearance_m = 0.0;
      return check;
    }
    // Distances to the four sides of its cell; only a side nearer than the
    // cap can bring a neighbour within it.
    const int64_t cx = FloorInt(x.x() / kCell), cy = FloorInt(x.y() / kCell);
    const double west = x.x() - static_cast<double>(cx) * kCell;
    const double south = x.y() - static_cast<double>(cy) * kCell;
    const double east = kCell - west, north = kCell - south;
    if (west >= kCap && east >= kCap && south >= kCap && north >= kCap) continue;
    double& c = check.clearance_m;
    const auto side = [&](double d, int dx, int dy) {
      if (d < c && free_at(cx, cy, dx, dy)) c = d;
    };
    side(west, -1, 0);
    side(east, 1, 0);
    side(south, 0, -1);
    side(north, 0, 1);
    // A diagonal neighbour is at least as far as the farther of its two sides.
    side(std::max(west, south), -1, -1);
    side(std::max(east, south), 1, -1);
    side(std::max(west, north), -1, 1);
    side(std::max(east, north), 1, 1);
  }
  check.clearance_m = std::max(0.0, check.clearance_m);
  return check;
}

double SampleShiftBound(const Segment2& from, const Segment2& to) {
  constexpr double kNone = std::numeric_limits<double>::infinity();
  const double l0 = from.length(), l1 = to.length();
  if (!(l0 > 2.0 * kPierceTrimM) || !(l1 > 2.0 * kPierceTrimM)) return kNone;
  if (SampleSteps(kPierceTrimM, l0 - kPierceTrimM) !=
      SampleSteps(kPierceTrimM, l1 - kPierceTrimM)) {
    return kNone;
  }
  // Sample i is (1 - w) a + w b with w = trim / L + (1 - 2 trim / L) i / steps
  // in [0, 1]. Moving a and b moves it by at most the larger end's shift,
  // plus |dw| L <= trim |L1 - L0| / L1 <= (|da| + |db|) / 2 (L1 > 2 trim).
  const double da = (to.a - from.a).norm(), db = (to.b - from.b).norm();
  return std::max(da, db) + 0.5 * (da + db) + kShiftSlackM;
}

}  // namespace mapd::fusion
