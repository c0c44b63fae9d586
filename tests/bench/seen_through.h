// Seen-through wall length (issue 40): how much of a published map's wall
// length lies where laser beams passed through, i.e. where the building has
// no wall. Benchmark support, not a library: it needs the raw beams, which
// the map server never receives.
//
// Definition (the one the issue states, unchanged): 10 cm cells; for every
// second scan, each beam with a return is sampled every 5 cm from the sensor
// to 15 cm before its hit, each sample counting one pass in the cell it lies
// in, and the hit counts one hit in its cell. A cell is seen through when
// passes >= 10 and passes >= 8 x hits. A segment's seen-through length is its
// length on such cells, sampled every 2 cm.
#ifndef MAPD_TESTS_BENCH_SEEN_THROUGH_H_
#define MAPD_TESTS_BENCH_SEEN_THROUGH_H_

#include <cstdint>
#include <vector>

#include "geometry/segment2.h"

namespace mapd::bench {

// One scan's beams with a return: the sensor position and the hit points,
// map frame, metres.
struct BeamFan {
  geometry::Vec2 origin_m = geometry::Vec2::Zero();
  const std::vector<geometry::Vec2>* hits_m = nullptr;
};

class SeenThroughGrid {
 public:
  static constexpr double kCellM = 0.1;
  static constexpr double kPassStepM = 0.05;
  static constexpr double kStopBeforeHitM = 0.15;
  static constexpr uint32_t kMinPasses = 10;
  static constexpr uint32_t kPassesPerHit = 8;
  static constexpr double kSegmentStepM = 0.02;

  // Every second fan (fans[0], fans[2], ...) is counted.
  explicit SeenThroughGrid(const std::vector<BeamFan>& fans);

  bool SeenThrough(const geometry::Vec2& p) const;
  // Metres of `s` on seen-through cells (midpoints of 2 cm steps).
  double SeenThroughLength(const geometry::Segment2& s) const;

  // Sums over segments.
  struct Totals {
    double seen_through_m = 0.0;
    double published_m = 0.0;
  };
  Totals Measure(const std::vector<geometry::Segment2>& segments) const;

 private:
  int64_t Index(const geometry::Vec2& p) const;  // -1 outside the grid

  geometry::Vec2 lo_ = geometry::Vec2::Zero();
  int64_t width_ = 0, height_ = 0;
  std::vector<uint32_t> passes_, hits_;
};

}  // namespace mapd::bench

#endif  // MAPD_TESTS_BENCH_SEEN_THROUGH_H_
