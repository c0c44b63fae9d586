#include "bench/carmen.h"

#include <cmath>

#include "client/robot/split_and_merge.h"

namespace mapd::bench {

double BeamAngle(size_t i, size_t n) {
  return -M_PI / 2.0 + static_cast<double>(i) * M_PI / static_cast<double>(n);
}

geometry::Vec2 BeamPoint(const LaserScan& scan, size_t i) {
  const double angle = scan.theta_rad + BeamAngle(i, scan.ranges_m.size());
  const double r = scan.ranges_m[i];
  return {scan.x_m + r * std::cos(angle), scan.y_m + r * std::sin(angle)};
}

ScanLines ExtractLaserLines(const LaserScan& scan, double max_range_m) {
  robot::SplitAndMergeParams params;
  params.split_m = 0.05;
  params.min_points = 6;
  params.min_length_m = 0.3;
  params.max_gap_m = 0.5;
  ScanLines out;
  out.sensor_xy_m = geometry::Vec2(scan.x_m, scan.y_m);
  std::vector<geometry::Vec2> run;
  const auto flush = [&]() {
    for (const robot::ExtractedLine& line : robot::SplitAndMerge(run, params)) {
      out.lines.push_back(line.segment);
    }
    run.clear();
  };
  for (size_t i = 0; i < scan.ranges_m.size(); ++i) {
    const double r = scan.ranges_m[i];
    if (!(r > 0.0 && r < max_range_m)) {
      flush();
      continue;
    }
    const geometry::Vec2 p = BeamPoint(scan, i);
    out.points.push_back(p);
    run.push_back(p);
  }
  flush();
  return out;
}

const std::vector<LaserLogSpec>& LaserLogs() {
  static const std::vector<LaserLogSpec> kLogs = {
      {"intel", "intel-corrected.log.gz", 80.0},
      {"aces", "aces-corrected.log.gz", 50.0},
      {"freiburg-079", "freiburg-079-corrected.log.gz", 80.0},
  };
  return kLogs;
}

}  // namespace mapd::bench
