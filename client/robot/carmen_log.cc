#include "client/robot/carmen_log.h"

#include <zlib.h>

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

}  // namespace

StatusOr<std::vector<CarmenScan>> ReadCarmenLaserLog(const std::string& path) {
  GzFile file(gzopen(path.c_str(), "rb"));
  if (!file) return Status::NotFound("cannot open CARMEN log " + path);
  std::vector<CarmenScan> scans;
  std::string line;
  size_t line_number = 0;
  while (ReadLine(file.get(), &line)) {
    ++line_number;
    if (line.compare(0, 7, "FLASER ") != 0) continue;
    const std::string where = path + ":" + std::to_string(line_number);
    const char* cursor = line.c_str() + 7;
    double count = 0.0;
    if (!NextNumber(&cursor, &count) || count < 1.0 || count > 10000.0) {
      return Status::InvalidArgument(where + ": FLASER without a beam count");
    }
    CarmenScan scan;
    scan.ranges_m.resize(static_cast<size_t>(count));
    for (double& r : scan.ranges_m) {
      if (!NextNumber(&cursor, &r)) return Status::InvalidArgument(where + ": missing range");
    }
    double odom = 0.0;
    if (!NextNumber(&cursor, &scan.x_m) || !NextNumber(&cursor, &scan.y_m) ||
        !NextNumber(&cursor, &scan.theta_rad) || !NextNumber(&cursor, &odom) ||
        !NextNumber(&cursor, &odom) || !NextNumber(&cursor, &odom) ||
        !NextNumber(&cursor, &scan.timestamp_s)) {
      return Status::InvalidArgument(where + ": missing pose or timestamp");
    }
    scans.push_back(std::move(scan));
  }
  int error = Z_OK;
  gzerror(file.get(), &error);
  if (error != Z_OK && error != Z_STREAM_END) {
    return Status::InvalidArgument("CARMEN log " + path + " is not a valid gzip stream");
  }
  return scans;
}

LaserScan ToLaserScan(const CarmenScan& scan, double max_range_m) {
  LaserScan out;
  out.angle_min_rad = -M_PI / 2;
  out.angle_increment_rad =
      M_PI / static_cast<double>(std::max<std::size_t>(scan.ranges_m.size(), 1));
  out.range_max_m = max_range_m;
  out.ranges_m = scan.ranges_m;
  return out;
}

}  // namespace mapd::robot
