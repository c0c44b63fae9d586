#include "bench/carmen.h"

#include <zlib.h>

#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <memory>

#include "client/robot/split_and_merge.h"

namespace mapd::bench {
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

StatusOr<std::vector<LaserScan>> ReadCarmenLaserLog(const std::string& path) {
  GzFile file(gzopen(path.c_str(), "rb"));
  if (!file) return Status::NotFound("cannot open CARMEN log " + path);
  std::vector<LaserScan> scans;
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
    LaserScan scan;
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
