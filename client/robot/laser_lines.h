// Line observations from a 2D laser scan, as a robot makes them before it
// sends a batch: the scan's returns become points in the sensor frame (x
// ahead, y to the left, metres), consecutive points form runs, and each run
// is cut into straight pieces and fitted by split-and-merge
// (split_and_merge.h). A beam without a return ends a run, so no line ever
// bridges a doorway, an occlusion or a missing return.
//
// The lines stay in the sensor frame: the batch carries the sensor pose
// (observation_batch.h), and mapd moves them into its frame.
#ifndef MAPD_CLIENT_ROBOT_LASER_LINES_H_
#define MAPD_CLIENT_ROBOT_LASER_LINES_H_

#include <vector>

#include "client/robot/split_and_merge.h"
#include "common/status.h"

namespace mapd::robot {

// One scan, as sensor_msgs/LaserScan carries it. Beam i points at
// angles_rad[i] when angles_rad is given (one per range, e.g. a scan that
// skips beams), else at angle_min_rad + i * angle_increment_rad;
// counter-clockwise from the sensor's x axis, radians.
struct LaserScan {
  double angle_min_rad = 0.0;
  double angle_increment_rad = 0.0;
  std::vector<double> angles_rad;  // empty: from angle_min_rad and angle_increment_rad
  // A range r is a return when range_min_m < r < range_max_m. NaN, +inf, and
  // readings at or beyond range_max_m (many lasers report their maximum when
  // nothing reflected) are no return: they end a run. A negative range is bad
  // input, not "no return".
  double range_min_m = 0.0;
  double range_max_m = 0.0;
  std::vector<double> ranges_m;
};

// Split-and-merge's settings for a laser (the steps of split_and_merge.h).
// The defaults are those of the real-log benchmark (docs/fusion-real-data.md):
// a 5 cm straightness tolerance, 6 points and 0.3 m per line, runs cut at
// gaps over max_gap_m + gap_per_range * range.
struct LineExtractionParams {
  double split_m = 0.05;      // max point-to-chord distance inside one line, metres: (0, 10]
  int min_points = 6;         // returns a line needs: [2, 100000]
  double min_length_m = 0.3;  // shorter fitted lines are dropped, metres: [0, 1000]
  double max_gap_m = 0.5;     // consecutive returns farther apart start a new run: (0, 1000]
  // Added to max_gap_m per metre of range: neighbouring beams d_theta apart
  // hit a wall r away about r d_theta apart, so a gap limit that grows with
  // range (e.g. 4 x the beam spacing in radians) keeps far walls whole. [0, 10]
  double gap_per_range = 0.0;

  Status Validate() const;  // InvalidArgument naming the field
};

// The lines of `scan` in the sensor frame, in beam order. InvalidArgument
// (naming the field and the beam) for bad settings, a scan with no beams, a
// non-finite or zero angle increment, a range window that is not
// 0 <= range_min_m < range_max_m <= 100 km, angles_rad of another length than
// ranges_m or not finite, and a negative range. A scan with no lines in it
// (all no return, or too few points) gives an empty list.
StatusOr<std::vector<ExtractedLine>> ExtractLines(const LaserScan& scan,
                                                  const LineExtractionParams& params);

}  // namespace mapd::robot

#endif  // MAPD_CLIENT_ROBOT_LASER_LINES_H_
