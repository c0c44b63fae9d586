// Split-and-merge line extraction from one ordered 2D scan (Pavlidis & Horowitz
// 1974; the "split-and-merge" of Nguyen et al., "A comparison of line extraction
// algorithms using 2D laser rangefinder data", IROS 2005, algorithm 1).
//
//  1. Runs: consecutive points farther apart than the gap limit start a new run,
//     so a segment never bridges a gap (an occlusion, a door, a missing return);
//     a non-finite point (a beam without a return) ends a run too. The limit is
//     max_gap_m + gap_per_range * (the larger distance of the two points from
//     the origin): neighbouring beams d_theta apart hit a wall r away about
//     r d_theta apart, so points in the sensor frame want a gap growing with range.
//  2. Split: a run is split recursively at the point farthest from the chord
//     through its first and last point while that distance exceeds split_m.
//  3. Merge: adjacent pieces of one run are joined when the point of the joined
//     set farthest from its chord is within split_m.
//  4. Fit: each piece with at least min_points points is fitted by total least
//     squares (geometry/line_fit.h) and clipped to the extreme projections of its
//     points; pieces shorter than min_length_m are dropped.
// Pure function of its input; no state.
#ifndef MAPD_GEOMETRY_SPLIT_AND_MERGE_H_
#define MAPD_GEOMETRY_SPLIT_AND_MERGE_H_

#include <cstddef>
#include <vector>

#include "geometry/segment2.h"

namespace mapd::geometry {

struct SplitAndMergeParams {
  double split_m = 0.05;       // max point-to-chord distance inside one segment, metres
  size_t min_points = 6;       // points a segment needs (>= 2)
  double min_length_m = 0.3;   // shorter fitted segments are dropped, metres
  double max_gap_m = 0.3;      // consecutive points farther apart start a new run, metres
  double gap_per_range = 0.0;  // added to max_gap_m per metre of range (e.g. 4 d_theta); 0: fixed
};

struct ExtractedLine {
  Segment2 segment;   // TLS fit clipped to the extreme projections, metres
  size_t first = 0;   // index of the first point of the piece in the input
  size_t last = 0;    // index of the last point (inclusive)
  double rms_m = 0.0; // RMS orthogonal distance of the piece's points to the fit
};

// Lines of an ordered scan (e.g. beam order), in the frame of `points`.
// Non-finite points (missing returns) belong to no line.
// REQUIRES: params.min_points >= 2; split_m, max_gap_m > 0; gap_per_range >= 0.
std::vector<ExtractedLine> SplitAndMerge(const std::vector<Vec2>& points,
                                         const SplitAndMergeParams& params);

}  // namespace mapd::geometry

#endif  // MAPD_GEOMETRY_SPLIT_AND_MERGE_H_
