// A reader for CARMEN laser logs (the Radish data sets in shared/data/laser):
// the FLASER lines of a plain or gzip-compressed log. Benchmark support, not a
// library: the map server never reads CARMEN.
//
//   FLASER n r_1 .. r_n x y theta odom_x odom_y odom_theta timestamp host logger_timestamp
//
// Ranges in metres; the n beams span 180 degrees from the robot's right to its
// left; x y theta is the (corrected) laser pose in the map frame.
#ifndef MAPD_TESTS_BENCH_CARMEN_H_
#define MAPD_TESTS_BENCH_CARMEN_H_

#include <string>
#include <vector>

#include "common/status.h"
#include "geometry/segment2.h"

namespace mapd::bench {

struct LaserScan {
  std::vector<double> ranges_m;
  double x_m = 0.0;  // laser pose in the map frame
  double y_m = 0.0;
  double theta_rad = 0.0;
  double timestamp_s = 0.0;
};

// Every FLASER line of `path` (gzip or plain, detected by zlib), in file order.
// NotFound if the file cannot be opened; InvalidArgument naming the line if a
// FLASER line is malformed.
StatusOr<std::vector<LaserScan>> ReadCarmenLaserLog(const std::string& path);

// The bearing of beam i of n in the laser frame, radians: -pi/2 + i * pi / n
// (the CARMEN/GMapping convention for 180- and 360-beam SICK scans, whose last
// beam falls one step short of +pi/2).
double BeamAngle(size_t i, size_t n);

// Beam i as a point in the map frame.
geometry::Vec2 BeamPoint(const LaserScan& scan, size_t i);

}  // namespace mapd::bench

#endif  // MAPD_TESTS_BENCH_CARMEN_H_
