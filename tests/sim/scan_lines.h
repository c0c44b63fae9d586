// Line extraction from one 2D scan by split-and-merge (Nguyen et al., "A
// comparison of line extraction algorithms using 2D laser rangefinder", 2005):
// consecutive returns are cut into runs at range jumps, each run is split
// recursively at the point farthest from its chord, and every piece with enough
// points is fitted by total least squares; its endpoints are the projections of
// its first and last points.
#ifndef MAPD_SIM_SCAN_LINES_H_
#define MAPD_SIM_SCAN_LINES_H_

#include <vector>

#include "geometry/segment2.h"

namespace mapd::fusion::scenario {

struct ExtractionParams {
  double split_m = 0.08;      // split while a point is farther than this from the chord
  double break_base_m = 0.3;  // a run breaks where consecutive points are farther apart
  double break_factor = 4.0;  //   than break_base_m + break_factor * r * beam_angle
  int min_points = 8;
  double min_length_m = 0.5;
};

struct ExtractedLine {
  geometry::Segment2 segment;  // sensor frame, metres
  int first = 0;               // beam indices of the points used (inclusive)
  int last = 0;
};

// points[b] is beam b's return in the sensor frame, valid[b] whether there is one.
std::vector<ExtractedLine> ExtractLines(const std::vector<geometry::Vec2>& points,
                                        const std::vector<bool>& valid, double beam_angle_rad,
                                        const ExtractionParams& params);

}  // namespace mapd::fusion::scenario

#endif  // MAPD_SIM_SCAN_LINES_H_
