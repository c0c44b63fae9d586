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
// The variant options of SplitAndMergeParams change steps 1-4 in small ways; the
// defaults are the steps as written here.
// Pure function of its input; no state.
#ifndef MAPD_CLIENT_ROBOT_SPLIT_AND_MERGE_H_
#define MAPD_CLIENT_ROBOT_SPLIT_AND_MERGE_H_

#include <cstddef>
#include <vector>

#include "geometry/segment2.h"

namespace mapd::robot {

using geometry::Segment2;
using geometry::Vec2;

struct SplitAndMergeParams {
  double split_m = 0.05;       // max point-to-chord distance inside one segment, metres
  size_t min_points = 6;       // points a segment needs (>= 2)
  double min_length_m = 0.3;   // shorter fitted segments are dropped, metres
  double max_gap_m = 0.3;      // consecutive points farther apart start a new run, metres
  double gap_per_range = 0.0;  // added to max_gap_m per metre of range (e.g. 4 d_theta); 0: fixed

  // Variants. Two extractors feed the fusion benchmarks, and their published
  // figures were measured with different choices at four places:
  //  - the defaults: the laser benchmark on the real CARMEN logs
  //    (docs/fusion-real-data.md) and `mapctl simulate` (client/sim_robot.cc);
  //  - all four flipped: the synthetic city (tests/sim/city_scenario.cc,
  //    docs/fusion.md). Running the city with the defaults moves its figures
  //    (seed 1: proposed-method vertex error 0.15 -> 0.18 cm, lateral RMS
  //    0.19 -> 0.23 cm, mean-shift vertex error 1.80 -> 2.85 cm; the break point
  //    alone: 0.18 and 2.57 cm), so each set of figures keeps its variant.
  //
  // Step 2: where the break point goes. true: it ends one piece and starts the
  // next (Nguyen et al.), so both walls of a corner hit exactly at a beam reach it.
  // false: only the first piece keeps it. The farthest point is rarely the corner
  // itself in a noisy scan (it lies on one of the two walls), and in both pieces
  // it pulls the fit of the wall it is not on.
  bool split_point_in_both = true;
  // Step 3 on/off. Off, a piece stays as the split left it, even when it and its
  // neighbour would pass the straightness test joined.
  bool merge_neighbours = true;
  // Step 1: the range that scales gap_per_range. true: the larger of the two
  // points' distances (symmetric in scan order). false: the distance of the point
  // that would join the run (the later one in the input order).
  bool gap_from_farther_point = true;
  // Step 4: the segment's ends. true: the extreme projections of all the piece's
  // points (the segment covers all its evidence; a/b along the canonical line
  // direction). false: the projections of the piece's first and last points (a/b
  // in input order; a noisy interior point does not stretch the segment).
  bool clip_to_extremes = true;
};

struct ExtractedLine {
  Segment2 segment;    // TLS fit, ends as clip_to_extremes says, metres
  size_t first = 0;    // index of the first point of the piece in the input
  size_t last = 0;     // index of the last point (inclusive)
  double rms_m = 0.0;  // RMS orthogonal distance of the piece's points to the fit
};

// Lines of an ordered scan (e.g. beam order), in the frame of `points`.
// Non-finite points (missing returns) belong to no line.
// REQUIRES: params.min_points >= 2; split_m, max_gap_m > 0; gap_per_range >= 0.
std::vector<ExtractedLine> SplitAndMerge(const std::vector<Vec2>& points,
                                         const SplitAndMergeParams& params);

}  // namespace mapd::robot

#endif  // MAPD_CLIENT_ROBOT_SPLIT_AND_MERGE_H_
