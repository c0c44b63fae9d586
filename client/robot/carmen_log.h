// CARMEN laser logs (the Radish data sets, e.g. intel, aces, freiburg-079):
// the FLASER lines of a plain or gzip-compressed log, for replaying a
// recorded robot (mapctl replay) and for the benchmarks.
//
//   FLASER n r_1 .. r_n x y theta odom_x odom_y odom_theta timestamp host logger_timestamp
//
// Ranges in metres; the n beams span 180 degrees from the robot's right to
// its left (-pi/2 + i * pi / n: the CARMEN/GMapping convention for 180- and
// 360-beam SICK scans, whose last beam falls one step short of +pi/2); x y
// theta is the laser pose in the log's frame (corrected logs: the map frame).
#ifndef MAPD_CLIENT_ROBOT_CARMEN_LOG_H_
#define MAPD_CLIENT_ROBOT_CARMEN_LOG_H_

#include <string>
#include <vector>

#include "client/robot/laser_lines.h"
#include "common/status.h"

namespace mapd::robot {

struct CarmenScan {
  std::vector<double> ranges_m;
  double x_m = 0.0;  // laser pose in the log's frame
  double y_m = 0.0;
  double theta_rad = 0.0;
  double timestamp_s = 0.0;  // seconds since the Unix epoch
};

// Every FLASER line of `path` (gzip or plain, detected by zlib), in file
// order. NotFound if the file cannot be opened; InvalidArgument naming the
// line if a FLASER line is malformed.
StatusOr<std::vector<CarmenScan>> ReadCarmenLaserLog(const std::string& path);

// The scan for ExtractLines: the 180 degree fan above, readings at or beyond
// max_range_m no return (FLASER does not carry the laser's maximum).
LaserScan ToLaserScan(const CarmenScan& scan, double max_range_m);

}  // namespace mapd::robot

#endif  // MAPD_CLIENT_ROBOT_CARMEN_LOG_H_
