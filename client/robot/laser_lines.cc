#include "client/robot/laser_lines.h"

#include <cmath>
#include <cstddef>
#include <limits>
#include <string>

namespace mapd::robot {
namespace {

constexpr double kMaxRangeM = 100'000.0;  // no laser sees farther; a bigger value is a unit error

std::string Number(double x) {
  std::string s = std::to_string(x);
  // "0.050000" -> "0.05": the value as the caller wrote it, near enough.
  if (s.find('.') != std::string::npos) {
    while (s.back() == '0') s.pop_back();
    if (s.back() == '.') s.pop_back();
  }
  return s;
}

Status Check(bool ok, const std::string& field, double value, const char* allowed) {
  if (ok) return Status::Ok();
  return Status::InvalidArgument(field + " is " + Number(value) + ", allowed: " + allowed);
}

Status CheckScan(const LaserScan& scan) {
  if (scan.ranges_m.empty()) return Status::InvalidArgument("scan.ranges_m is empty: no beams");
  if (!std::isfinite(scan.range_min_m) || scan.range_min_m < 0) {
    return Check(false, "scan.range_min_m", scan.range_min_m, "finite, >= 0");
  }
  if (!(scan.range_max_m > scan.range_min_m && scan.range_max_m <= kMaxRangeM)) {
    return Check(false, "scan.range_max_m", scan.range_max_m,
                 "above range_min_m and at most 100000 m");
  }
  if (scan.angles_rad.empty()) {
    if (!std::isfinite(scan.angle_min_rad)) {
      return Check(false, "scan.angle_min_rad", scan.angle_min_rad, "finite");
    }
    if (!std::isfinite(scan.angle_increment_rad) || scan.angle_increment_rad == 0) {
      return Check(false, "scan.angle_increment_rad", scan.angle_increment_rad,
                   "finite and not 0 (or give angles_rad)");
    }
  } else if (scan.angles_rad.size() != scan.ranges_m.size()) {
    return Status::InvalidArgument("scan.angles_rad has " + std::to_string(scan.angles_rad.size()) +
                                   " angles for " + std::to_string(scan.ranges_m.size()) +
                                   " ranges: give one per range, or none");
  }
  for (std::size_t i = 0; i < scan.angles_rad.size(); ++i) {
    if (!std::isfinite(scan.angles_rad[i])) {
      return Check(false, "scan.angles_rad[" + std::to_string(i) + "]", scan.angles_rad[i],
                   "finite");
    }
  }
  for (std::size_t i = 0; i < scan.ranges_m.size(); ++i) {
    // NaN and +inf are "no return"; a negative range is not a reading at all.
    if (scan.ranges_m[i] < 0) {
      return Check(false, "scan.ranges_m[" + std::to_string(i) + "]", scan.ranges_m[i],
                   ">= 0, or NaN / inf for no return");
    }
  }
  return Status::Ok();
}

}  // namespace

Status LineExtractionParams::Validate() const {
  MAPD_RETURN_IF_ERROR(
      Check(split_m > 0 && split_m <= 10, "line extraction split_m", split_m, "(0, 10] m"));
  MAPD_RETURN_IF_ERROR(Check(min_points >= 2 && min_points <= 100'000, "line extraction min_points",
                             min_points, "[2, 100000]"));
  MAPD_RETURN_IF_ERROR(Check(min_length_m >= 0 && min_length_m <= 1000,
                             "line extraction min_length_m", min_length_m, "[0, 1000] m"));
  MAPD_RETURN_IF_ERROR(Check(max_gap_m > 0 && max_gap_m <= 1000, "line extraction max_gap_m",
                             max_gap_m, "(0, 1000] m"));
  return Check(gap_per_range >= 0 && gap_per_range <= 10, "line extraction gap_per_range",
               gap_per_range, "[0, 10] m per m");
}

StatusOr<std::vector<ExtractedLine>> ExtractLines(const LaserScan& scan,
                                                  const LineExtractionParams& params) {
  MAPD_RETURN_IF_ERROR(params.Validate());
  MAPD_RETURN_IF_ERROR(CheckScan(scan));
  // One point per beam, NaN for no return: SplitAndMerge ends a run there,
  // and an ExtractedLine's first and last are beam indices.
  const double nan = std::numeric_limits<double>::quiet_NaN();
  std::vector<Vec2> points(scan.ranges_m.size(), Vec2(nan, nan));
  for (std::size_t i = 0; i < scan.ranges_m.size(); ++i) {
    const double r = scan.ranges_m[i];
    if (!(r > scan.range_min_m && r < scan.range_max_m)) continue;  // NaN fails too
    const double angle = scan.angles_rad.empty() ? scan.angle_min_rad + static_cast<double>(i) *
                                                                            scan.angle_increment_rad
                                                 : scan.angles_rad[i];
    points[i] = Vec2(r * std::cos(angle), r * std::sin(angle));
  }
  SplitAndMergeParams sm;
  sm.split_m = params.split_m;
  sm.min_points = static_cast<std::size_t>(params.min_points);
  sm.min_length_m = params.min_length_m;
  sm.max_gap_m = params.max_gap_m;
  sm.gap_per_range = params.gap_per_range;
  return SplitAndMerge(points, sm);
}

}  // namespace mapd::robot
