#include "client/robot/carmen_log.h"

#include <zlib.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <type_traits>

namespace mapd::robot {
namespace {

struct GzCloser {
  void operator()(gzFile f) const { gzclose(f); }
};
using GzFile = std::unique_ptr<std::remove_pointer_t<gzFile>, GzCloser>;

// Reads one whole line (any length) into `line`, without the newline.
bool ReadLine(gzFile f, std::string* line) {
  line->clear();
  char buffer[8192];
  while (gzgets(f, buffer, sizeof(buffer)) != nullptr) {
    line->append(buffer);
    if (!line->empty() && line->back() == '\n') {
      line->pop_back();
      return true;
    }
  }
  return !line->empty();
}

// Parses the next number of `*cursor`, advancing it; false if there is none.
bool NextNumber(const char** cursor, double* value) {
  char* end = nullptr;
  errno = 0;
  *value = std::strtod(*cursor, &end);
  if (end == *cursor || errno == ERANGE) return false;
  *cursor = end;
  return true;
}

// Reads `count` numbers of `*cursor` into `out` (resized); false if short.
bool NextNumbers(const char** cursor, double count, std::vector<double>* out) {
  if (!(count >= 0.0 && count <= 100000.0)) return false;
  out->resize(static_cast<size_t>(count));
  for (double& v : *out) {
    if (!NextNumber(cursor, &v)) return false;
  }
  return true;
}

// One FLASER line after its keyword.
Status ParseFlaser(const char* cursor, const std::string& where, CarmenScan* scan) {
  double count = 0.0;
  if (!NextNumber(&cursor, &count) || count < 1.0 || count > 10000.0) {
    return Status::InvalidArgument(where + ": FLASER without a beam count");
  }
  if (!NextNumbers(&cursor, count, &scan->ranges_m)) {
    return Status::InvalidArgument(where + ": missing range");
  }
  double odom = 0.0;
  if (!NextNumber(&cursor, &scan->x_m) || !NextNumber(&cursor, &scan->y_m) ||
      !NextNumber(&cursor, &scan->theta_rad) || !NextNumber(&cursor, &odom) ||
      !NextNumber(&cursor, &odom) || !NextNumber(&cursor, &odom) ||
      !NextNumber(&cursor, &scan->timestamp_s)) {
    return Status::InvalidArgument(where + ": missing pose or timestamp");
  }
  return Status::Ok();
}

// One ROBOTLASER1 line after its keyword.
Status ParseRobotLaser(const char* cursor, const std::string& where, CarmenScan* scan) {
  double type = 0.0, fov = 0.0, accuracy = 0.0, remission_mode = 0.0, count = 0.0;
  if (!NextNumber(&cursor, &type) || !NextNumber(&cursor, &scan->angle_min_rad) ||
      !NextNumber(&cursor, &fov) || !NextNumber(&cursor, &scan->angle_increment_rad) ||
      !NextNumber(&cursor, &scan->max_range_m) || !NextNumber(&cursor, &accuracy) ||
      !NextNumber(&cursor, &remission_mode)) {
    return Status::InvalidArgument(where + ": ROBOTLASER1 without its laser settings");
  }
  if (!std::isfinite(scan->angle_min_rad) || !(scan->angle_increment_rad > 0.0) ||
      !std::isfinite(scan->angle_increment_rad) || !(scan->max_range_m >= 0.0)) {
    return Status::InvalidArgument(where +
                                   ": ROBOTLASER1 needs a finite start angle, a positive "
                                   "angular resolution and a maximum range >= 0");
  }
  if (!NextNumber(&cursor, &count) || count < 1.0 || count > 10000.0) {
    return Status::InvalidArgument(where + ": ROBOTLASER1 without a beam count");
  }
  if (!NextNumbers(&cursor, count, &scan->ranges_m)) {
    return Status::InvalidArgument(where + ": missing range");
  }
  std::vector<double> skipped;
  if (!NextNumber(&cursor, &count) || !NextNumbers(&cursor, count, &skipped)) {
    return Status::InvalidArgument(where + ": missing remissions");
  }
  if (!NextNumber(&cursor, &scan->x_m) || !NextNumber(&cursor, &scan->y_m) ||
      !NextNumber(&cursor, &scan->theta_rad) || !NextNumbers(&cursor, 8, &skipped) ||
      !NextNumber(&cursor, &scan->timestamp_s)) {
    return Status::InvalidArgument(where + ": missing pose or timestamp");
  }
  return Status::Ok();
}

}  // namespace

StatusOr<std::vector<CarmenScan>> ReadCarmenLaserLog(const std::string& path) {
  GzFile file(gzopen(path.c_str(), "rb"));
  if (!file) return Status::NotFound("cannot open CARMEN log " + path);
  std::vector<CarmenScan> flaser, robotlaser;
  std::string line;
  size_t line_number = 0;
  while (ReadLine(file.get(), &line)) {
    ++line_number;
    const bool is_flaser = line.compare(0, 7, "FLASER ") == 0;
    const bool is_robotlaser = line.compare(0, 12, "ROBOTLASER1 ") == 0;
    if (!is_flaser && !is_robotlaser) continue;
    const std::string where = path + ":" + std::to_string(line_number);
    CarmenScan scan;
    if (is_flaser) {
      MAPD_RETURN_IF_ERROR(ParseFlaser(line.c_str() + 7, where, &scan));
      flaser.push_back(std::move(scan));
    } else {
      MAPD_RETURN_IF_ERROR(ParseRobotLaser(line.c_str() + 12, where, &scan));
      robotlaser.push_back(std::move(scan));
    }
  }
  int error = Z_OK;
  gzerror(file.get(), &error);
  if (error != Z_OK && error != Z_STREAM_END) {
    return Status::InvalidArgument("CARMEN log " + path + " is not a valid gzip stream");
  }
  return robotlaser.empty() ? flaser : robotlaser;
}

LaserScan ToLaserScan(const CarmenScan& scan, double max_range_m) {
  LaserScan out;
  out.angle_min_rad = scan.angle_min_rad;
  out.angle_increment_rad =
      scan.angle_increment_rad > 0.0
          ? scan.angle_increment_rad
          : M_PI / static_cast<double>(std::max<std::size_t>(scan.ranges_m.size(), 1));
  out.range_max_m = scan.max_range_m > 0.0 ? std::min(scan.max_range_m, max_range_m) : max_range_m;
  out.ranges_m = scan.ranges_m;
  return out;
}

}  // namespace mapd::robot
