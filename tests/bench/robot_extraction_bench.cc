// The robot library's laser extractor (client/robot/laser_lines.h) on the
// shared CARMEN logs, as a robot calls it: one scan at a time, sensor frame.
// Prints, per log, the extraction CPU time per scan and per beam and the
// lines per scan (docs/robot-library.md). Run on demand, not by ctest.
//
//   robot_extraction_bench [DATA_DIR] [--repeat=N]
//
// DATA_DIR defaults to ../shared/data/laser beside the source tree.
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <fstream>
#include <string>
#include <vector>

#include "bench/carmen.h"
#include "client/robot/laser_lines.h"

namespace {

double CpuSeconds() {
  timespec t{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

}  // namespace

int main(int argc, char** argv) {
  std::string dir = std::string(MAPD_SOURCE_DIR) + "/../shared/data/laser";
  int repeat = 20;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg.rfind("--repeat=", 0) == 0) {
      repeat = std::atoi(arg.c_str() + 9);
      if (repeat < 1) {
        std::fprintf(stderr, "--repeat must be >= 1, got %s\n", arg.c_str() + 9);
        return 2;
      }
    } else {
      dir = arg;
    }
  }
  std::printf(
      "| log | scans | beams per scan | lines per scan | CPU per scan (us) | CPU per beam (ns) "
      "|\n");
  std::printf("|---|---|---|---|---|---|\n");
  int logs = 0;
  for (const mapd::bench::LaserLogSpec& spec : mapd::bench::LaserLogs()) {
    const std::string path = dir + "/" + spec.file;
    if (!std::ifstream(path).good()) continue;
    const auto scans = mapd::bench::ReadCarmenLaserLog(path);
    if (!scans.ok()) {
      std::fprintf(stderr, "%s: %s\n", path.c_str(), scans.status().message().c_str());
      return 1;
    }
    ++logs;
    // Scans as a robot holds them (the pose is not the extractor's business).
    std::vector<mapd::robot::LaserScan> robot_scans;
    std::size_t beams = 0;
    for (const mapd::bench::LaserScan& carmen : *scans) {
      mapd::robot::LaserScan scan;
      scan.angle_min_rad = -M_PI / 2;
      scan.angle_increment_rad = M_PI / static_cast<double>(carmen.ranges_m.size());
      scan.range_max_m = spec.max_range_m;
      scan.ranges_m = carmen.ranges_m;
      beams += scan.ranges_m.size();
      robot_scans.push_back(std::move(scan));
    }
    std::size_t lines = 0;
    const mapd::robot::LineExtractionParams params;
    const double start = CpuSeconds();
    for (int r = 0; r < repeat; ++r) {
      for (const mapd::robot::LaserScan& scan : robot_scans) {
        const auto extracted = mapd::robot::ExtractLines(scan, params);
        if (!extracted.ok()) {
          std::fprintf(stderr, "%s\n", extracted.status().message().c_str());
          return 1;
        }
        if (r == 0) lines += extracted->size();
      }
    }
    const double cpu = (CpuSeconds() - start) / repeat;
    const auto n = static_cast<double>(robot_scans.size());
    std::printf("| %s | %zu | %.0f | %.1f | %.1f | %.0f |\n", spec.name, robot_scans.size(),
                static_cast<double>(beams) / n, static_cast<double>(lines) / n, 1e6 * cpu / n,
                1e9 * cpu / static_cast<double>(beams));
  }
  if (logs == 0) {
    std::printf("no CARMEN logs in %s: nothing measured\n", dir.c_str());
  }
  return 0;
}
