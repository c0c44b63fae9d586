// The robot library's plane extractor (client/robot/cloud_planes.h) as a robot
// runs it, one scan at a time: RANSAC against region growing, organised
// against unorganised, on
//   - simulated 16-beam LiDAR scans along the synthetic city's route (tests/sim),
//     where every point's surface is known;
//   - the real 3D scan of the shared data folder (pointcloud/scan.dat.bz2,
//     88,206 points, no order, no labels), read by the library's text reader.
// Prints Markdown tables (docs/robot-library.md). Run on demand, not by ctest.
//
//   cloud_planes_bench [--data DIR] [--city-step M]
//
// --data: the shared data folder (default $MAPD_SHARED_DIR/data, else
// ../shared/data beside the source tree); --city-step: route metres between
// city scans (default 4).
#include <pcl/filters/voxel_grid.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <iterator>
#include <map>
#include <set>
#include <string>
#include <vector>

#include "client/robot/cloud_files.h"
#include "client/robot/cloud_planes.h"
#include "client/robot/pcl_cloud.h"
#include "sim/city_scenario.h"
#include "sim/city_world.h"
#include "sim/lidar_sim.h"

namespace mapd::bench {
namespace {

namespace sc = fusion::scenario;
using robot::PlaneExtractionParams;
using robot::PlaneSegmentation;

double CpuSeconds() {
  timespec t{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

struct Method {
  const char* name;
  PlaneSegmentation segmentation;
  bool organised;
};

constexpr Method kMethods[] = {
    {"RANSAC, organised (default for a LiDAR)", PlaneSegmentation::kRansac, true},
    {"RANSAC, unorganised", PlaneSegmentation::kRansac, false},
    {"region growing, organised", PlaneSegmentation::kRegionGrowing, true},
    {"region growing, unorganised", PlaneSegmentation::kRegionGrowing, false},
};

struct Score {
  size_t scans = 0, points = 0, planes = 0, pure = 0, merged = 0;
  size_t surfaces_seen = 0, surfaces_found = 0;
  double cpu_s = 0.0;
};

std::vector<robot::ExtractedPlane> Run(const robot::OrganisedCloud& cloud, const Method& method,
                                       const std::vector<Eigen::Vector3f>& returns, double* cpu_s) {
  PlaneExtractionParams params;
  params.segmentation = method.segmentation;
  const double t = CpuSeconds();
  auto planes = method.organised ? robot::ExtractPlanes(cloud, params)
                                 : robot::ExtractPlanes(returns, params);
  *cpu_s += CpuSeconds() - t;
  if (!planes.ok()) {
    std::fprintf(stderr, "extraction failed: %s\n", planes.status().message().c_str());
    std::exit(1);
  }
  return std::move(planes).value();
}

int City(double step_m) {
  sc::ScenarioParams scenario;
  scenario.blocks_x = 4;
  scenario.blocks_y = 3;
  scenario.scan_spacing_m = step_m;
  const sc::World world = sc::GenerateWorld(scenario);
  const sim::CityWorld city(world, sim::CityHeights{});
  const sim::LidarSimulator lidar(sim::LidarParams{});
  std::vector<Score> scores(std::size(kMethods));
  for (size_t k = 0; k < world.route.size(); ++k) {
    const sc::Pose2& p = world.route[k];
    geometry::Rigid3 pose;
    pose.translation = {p.t.x(), p.t.y(), 1.8};
    pose.rotation = Eigen::Quaterniond(Eigen::AngleAxisd(p.yaw_rad, Eigen::Vector3d::UnitZ()));
    const sim::LidarScan scan = lidar.Scan(city, pose, k);
    robot::OrganisedCloud cloud;
    cloud.rows = scan.beams;
    cloud.columns = scan.columns;
    cloud.points = scan.points;
    cloud.wrap_columns = true;
    std::vector<Eigen::Vector3f> returns;  // the same points without their order
    std::vector<int> return_labels;
    std::map<int, size_t> per_surface;
    for (size_t i = 0; i < scan.points.size(); ++i) {
      if (!scan.points[i].allFinite()) continue;
      returns.push_back(scan.points[i]);
      return_labels.push_back(scan.labels[i]);
      ++per_surface[scan.labels[i]];
    }
    size_t seen = 0;
    for (const auto& [label, n] : per_surface) seen += n >= PlaneExtractionParams().min_inliers;
    for (size_t m = 0; m < std::size(kMethods); ++m) {
      Score& s = scores[m];
      const auto planes = Run(cloud, kMethods[m], returns, &s.cpu_s);
      const std::vector<int>& labels = kMethods[m].organised ? scan.labels : return_labels;
      std::set<int> found;
      for (const robot::ExtractedPlane& plane : planes) {
        std::map<int, size_t> votes;
        for (int i : plane.indices) ++votes[labels[static_cast<size_t>(i)]];
        size_t top = 0, second = 0;
        int top_label = -2;
        for (const auto& [label, n] : votes) {
          if (n > top) {
            second = top;
            top = n;
            top_label = label;
          } else {
            second = std::max(second, n);
          }
        }
        const double share = static_cast<double>(top) / static_cast<double>(plane.indices.size());
        if (share >= 0.95) {
          ++s.pure;
          found.insert(top_label);
        }
        if (static_cast<double>(second) >= 0.1 * static_cast<double>(plane.indices.size())) {
          ++s.merged;
        }
      }
      ++s.scans;
      s.points += returns.size();
      s.planes += planes.size();
      s.surfaces_seen += seen;
      s.surfaces_found += found.size();
    }
  }
  std::printf(
      "### Simulated city (%zu scans, %.0f returns a scan)\n\n"
      "| method | planes per scan | pure (>= 95 %% one surface) | merged (2 surfaces >= 10 %%) | "
      "surfaces found / seen (>= %zu returns) | CPU ms per scan | CPU ns per point |\n"
      "|---|---:|---:|---:|---:|---:|---:|\n",
      scores[0].scans, static_cast<double>(scores[0].points) / scores[0].scans,
      PlaneExtractionParams().min_inliers);
  for (size_t m = 0; m < std::size(kMethods); ++m) {
    const Score& s = scores[m];
    std::printf("| %s | %.2f | %.1f %% | %.1f %% | %.1f %% | %.1f | %.0f |\n", kMethods[m].name,
                static_cast<double>(s.planes) / s.scans,
                100.0 * s.pure / std::max<size_t>(s.planes, 1),
                100.0 * s.merged / std::max<size_t>(s.planes, 1),
                100.0 * s.surfaces_found / std::max<size_t>(s.surfaces_seen, 1),
                1e3 * s.cpu_s / s.scans, 1e9 * s.cpu_s / static_cast<double>(s.points));
  }
  return 0;
}

int RealScan(const std::string& data_dir) {
  const std::string packed = data_dir + "/pointcloud/scan.dat.bz2";
  char name[] = "/tmp/mapd-cloud-XXXXXX";
  const int fd = mkstemp(name);
  if (fd < 0) return 1;
  close(fd);
  const std::string text = std::string(name) + ".xyz";
  const std::string command = "bzip2 -dc '" + packed + "' > '" + text + "'";
  const int rc = std::system(command.c_str());
  std::remove(name);
  if (rc != 0) {
    std::fprintf(stderr, "cannot unpack %s (pass --data DIR)\n", packed.c_str());
    std::remove(text.c_str());
    return 1;
  }
  const double t0 = CpuSeconds();
  const auto file = robot::ReadCloudFile(text);
  const double read_s = CpuSeconds() - t0;
  std::remove(text.c_str());
  if (!file.ok()) {
    std::fprintf(stderr, "%s\n", file.status().message().c_str());
    return 1;
  }
  std::printf(
      "\n### The real scan (%zu points, unorganised; read in %.0f ms)\n\n"
      "| method | planes | points in a plane (of those extracted from) | median refit RMS (cm) | "
      "largest plane (points) | "
      "CPU ms | CPU ns per point |\n|---|---:|---:|---:|---:|---:|---:|\n",
      file->points.size(), 1e3 * read_s);
  // A dense cloud thinned first, as docs/robot-library.md advises: one point
  // (the centroid) per occupied 5 cm / 10 cm cell (pcl::VoxelGrid), inside the CPU time.
  struct Variant {
    const Method* method;
    double voxel_m;
  };
  std::vector<Variant> variants;
  for (const Method& method : kMethods) {
    if (!method.organised) variants.push_back({&method, 0.0});
  }
  variants.push_back({&kMethods[1], 0.05});
  variants.push_back({&kMethods[1], 0.10});
  for (const Variant& v : variants) {
    const Method& method = *v.method;
    double cpu_s = 0.0;
    std::vector<Eigen::Vector3f> points = file->points;
    if (v.voxel_m > 0) {
      const double t = CpuSeconds();
      pcl::PointCloud<pcl::PointXYZ>::Ptr in(new pcl::PointCloud<pcl::PointXYZ>),
          out(new pcl::PointCloud<pcl::PointXYZ>);
      for (const Eigen::Vector3f& p : points) in->push_back(pcl::PointXYZ(p.x(), p.y(), p.z()));
      pcl::VoxelGrid<pcl::PointXYZ> grid;
      grid.setInputCloud(in);
      const float leaf = static_cast<float>(v.voxel_m);
      grid.setLeafSize(leaf, leaf, leaf);
      grid.filter(*out);
      points = robot::ToPoints(*out);
      cpu_s += CpuSeconds() - t;
    }
    const auto planes = Run(robot::OrganisedCloud(), method, points, &cpu_s);
    size_t in_plane = 0, largest = 0;
    std::vector<double> rms;
    for (const robot::ExtractedPlane& p : planes) {
      in_plane += p.indices.size();
      largest = std::max(largest, p.indices.size());
      rms.push_back(p.rms_m);
    }
    std::sort(rms.begin(), rms.end());
    const std::string row_name =
        v.voxel_m > 0
            ? std::string(method.name) + ", " + std::to_string(std::lround(100 * v.voxel_m)) +
                  " cm voxel grid first (" + std::to_string(points.size()) + " points)"
            : std::string(method.name);
    std::printf("| %s | %zu | %.1f %% | %.1f | %zu | %.0f | %.0f |\n", row_name.c_str(),
                planes.size(), 100.0 * in_plane / points.size(),
                rms.empty() ? 0.0 : 100 * rms[rms.size() / 2], largest, 1e3 * cpu_s,
                1e9 * cpu_s / file->points.size());
  }
  return 0;
}

}  // namespace
}  // namespace mapd::bench

int main(int argc, char** argv) {
  const char* shared = std::getenv("MAPD_SHARED_DIR");
  std::string data_dir = shared != nullptr ? std::string(shared) + "/data"
                                           : std::string(MAPD_SOURCE_DIR) + "/../shared/data";
  double step_m = 4.0;
  for (int i = 1; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--data") && i + 1 < argc) {
      data_dir = argv[++i];
    } else if (!std::strcmp(argv[i], "--city-step") && i + 1 < argc) {
      step_m = std::atof(argv[++i]);
    } else {
      std::fprintf(stderr, "usage: %s [--data DIR] [--city-step M]\n", argv[0]);
      return 2;
    }
  }
  if (!(step_m >= 0.2)) {
    std::fprintf(stderr, "--city-step must be >= 0.2 m\n");
    return 2;
  }
  if (int rc = mapd::bench::City(step_m); rc != 0) return rc;
  return mapd::bench::RealScan(data_dir);
}
