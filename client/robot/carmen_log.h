// CARMEN laser logs (the Radish data sets, e.g. intel, aces, freiburg-079):
// the laser lines of a plain or gzip-compressed log, for replaying a
// recorded robot (mapctl replay) and for the benchmarks. Two line types:
//
//   FLASER n r_1 .. r_n x y theta odom_x odom_y odom_theta timestamp host logger_timestamp
//
// Ranges in metres; the n beams span 180 degrees from the robot's right to
// its left (-pi/2 + i * pi / n: the CARMEN/GMapping convention for 180- and
// 360-beam SICK scans, whose last beam falls one step short of +pi/2); x y
// theta is the laser pose in the log's frame (corrected logs: the map frame).
//
//   ROBOTLASER1 type start_angle fov resolution max_range accuracy remission_mode
//               n r_1 .. r_n m e_1 .. e_m laser_x laser_y laser_theta
//               robot_x robot_y robot_theta tv rv forward_safety side_safety
//               turn_axis timestamp host logger_timestamp
//
// The laser's own geometry: beam i at start_angle + i * resolution (radians,
// in the laser frame), readings at or beyond max_range no return; laser_x
// laser_y laser_theta its pose in the log's frame. CARMEN loggers often write
// both lines for one scan, so a log with any ROBOTLASER1 line is read from
// those alone.
#ifndef MAPD_CLIENT_ROBOT_CARMEN_LOG_H_
#define MAPD_CLIENT_ROBOT_CARMEN_LOG_H_

#include <cmath>
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
  // The beams (ROBOTLASER1); FLASER's 180 degree fan when increment is 0.
  double angle_min_rad = -M_PI / 2;
  double angle_increment_rad = 0.0;
  double max_range_m = 0.0;  // the laser's maximum; 0 when the log does not say
};

// Every ROBOTLASER1 line of `path` (gzip or plain, detected by zlib) in file
// order, or every FLASER line if it has none. NotFound if the file cannot be
// opened; InvalidArgument naming the line if a laser line is malformed.
StatusOr<std::vector<CarmenScan>> ReadCarmenLaserLog(const std::string& path);

// The scan for ExtractLines: the scan's beams (above), readings at or beyond
// max_range_m, or the laser's own maximum when the log gives a smaller one,
// no return (FLASER does not carry the laser's maximum).
LaserScan ToLaserScan(const CarmenScan& scan, double max_range_m);

}  // namespace mapd::robot

#endif  // MAPD_CLIENT_ROBOT_CARMEN_LOG_H_
