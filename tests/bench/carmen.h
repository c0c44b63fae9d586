// The benchmarks' view of the CARMEN laser logs in shared/data/laser (read by
// the robot library's reader, client/robot/carmen_log.h): the logs, and their
// lines extracted in the map frame as the fusion benchmarks used them.
#ifndef MAPD_TESTS_BENCH_CARMEN_H_
#define MAPD_TESTS_BENCH_CARMEN_H_

#include <string>
#include <vector>

#include "client/robot/carmen_log.h"
#include "common/status.h"
#include "geometry/segment2.h"

namespace mapd::bench {

using LaserScan = robot::CarmenScan;
using robot::ReadCarmenLaserLog;

// The bearing of beam i of n in the laser frame, radians: -pi/2 + i * pi / n
// (the CARMEN/GMapping convention for 180- and 360-beam SICK scans, whose last
// beam falls one step short of +pi/2).
double BeamAngle(size_t i, size_t n);

// Beam i as a point in the map frame.
geometry::Vec2 BeamPoint(const LaserScan& scan, size_t i);

// One scan's valid returns and the lines extracted from them, map frame.
struct ScanLines {
  std::vector<geometry::Vec2> points;     // valid returns (0 < range < max range)
  std::vector<geometry::Segment2> lines;  // split-and-merge (client/robot/split_and_merge.h)
  geometry::Vec2 sensor_xy_m = geometry::Vec2::Zero();  // the laser's position
};

// The valid beams in order, cut into runs at invalid ones, each run cut into
// lines (5 cm split, at least 6 points and 0.3 m, gaps up to 0.5 m).
ScanLines ExtractLaserLines(const LaserScan& scan, double max_range_m);

// The three logs of shared/data/laser with their "no return" ranges: Intel and
// Freiburg use 81.83 / 81.91 m (a SICK in 80 m mode), ACES 50 m.
struct LaserLogSpec {
  const char* name;    // short name, e.g. "intel"
  const char* file;    // under the data directory
  double max_range_m;  // readings at or beyond are "no return"
};
const std::vector<LaserLogSpec>& LaserLogs();

}  // namespace mapd::bench

#endif  // MAPD_TESTS_BENCH_CARMEN_H_
