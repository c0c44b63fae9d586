// Planes from a simulated 3D sensor through fusion (issue 10). A 16-beam
// LiDAR (tests/sim) drives (a) the synthetic city of sim/city_scenario.h, walls
// extruded to 6-20 m over the ground plane, and (b) the real OctoMap maps
// geb079 and fr_078_tidyup (rays cast with OcTree::castRay from poses sampled
// in known-free space). Each scan's planes (RANSAC, tests/sim/plane_extraction.h)
// go through fusion::ProjectToGround: near-vertical planes become ground
// segments for fusion::FusionEngine, the others MapPlanes for
// fusion::PlaneFusionEngine (plane_fusion_adapter.h). Prints markdown tables for docs/planes-3d.md
// and writes docs/planes-3d-<world>.svg.
//
//   plane_bench [--data DIR] [--docs DIR] [--no-write] [--scans N] [--city-step M]
// --data: the folder holding geb079.bt and fr_078_tidyup.bt (the shared data
// folder's data/octomap; default $MAPD_SHARED_DIR/data/octomap); --scans: poses per real map
// (default 80);
// --city-step: route metres between city scans (default 2).
#include <octomap/OcTree.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <map>
#include <set>
#include <string>
#include <unordered_set>
#include <vector>

#include "bench/plane_fusion_adapter.h"
#include "eval/metrics.h"
#include "eval/svg.h"
#include "fusion/engine.h"
#include "fusion/projection.h"
#include "geometry/segment2.h"
#include "sim/city_scenario.h"
#include "sim/city_world.h"
#include "sim/lidar_sim.h"
#include "sim/octomap_world.h"
#include "sim/plane_extraction.h"

namespace mapd::bench {
namespace {

namespace sc = fusion::scenario;
using geometry::Rigid3;
using geometry::Segment2;
using geometry::Vec2;

double Since(std::chrono::steady_clock::time_point t) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
}

// Everything one world's run produced.
struct Run {
  size_t scans = 0;
  size_t points = 0;
  size_t raw_planes = 0;
  size_t raw_vertical = 0;  // became ground segments
  size_t raw_other = 0;     // MapPlanes
  size_t skipped = 0;       // vertical planes whose projection degenerates
  double sim_s = 0.0, extract_s = 0.0, wall_fusion_s = 0.0;
  std::vector<fusion::FusedFeature> walls;
  PlaneFusionResult planes;
  std::vector<sc::Scan> raw;          // ground features per scan with truth labels (city metrics)
  std::vector<Eigen::Vector3d> hits;  // scan points in the map frame (real maps)
  std::vector<Rigid3> poses;
};

Status Drive(const sim::LidarWorld& world, const std::vector<Rigid3>& poses, bool keep_hits,
             Run* run) {
  const sim::LidarSimulator lidar(sim::LidarParams{});
  const sim::PlaneExtractionParams extraction;
  const fusion::FusionParams fparams;  // the defaults: bounded mode, min_support 3
  fusion::FusionEngine walls(fparams);
  PlaneFuser planes;
  run->poses = poses;
  for (size_t k = 0; k < poses.size(); ++k) {
    auto t = std::chrono::steady_clock::now();
    const sim::LidarScan scan = lidar.Scan(world, poses[k], k);
    run->sim_s += Since(t);
    run->points += scan.valid_count();
    if (keep_hits) {
      for (const auto& p : scan.points) {
        if (p.allFinite()) run->hits.push_back(poses[k] * p.cast<double>());
      }
    }
    t = std::chrono::steady_clock::now();
    auto extracted = sim::ExtractPlanes(scan, extraction);
    run->extract_s += Since(t);
    if (!extracted.ok()) return extracted.status();
    geometry::SensorObservation obs;
    obs.T_frame_sensor = poses[k];
    for (const auto& p : extracted.value()) obs.planes.push_back(p.feature);
    const fusion::FeatureId first = static_cast<fusion::FeatureId>(k) << 10;
    auto projected = fusion::ProjectToGround(obs, Rigid3::Identity(), first, fparams);
    if (!projected.ok()) return projected.status();
    run->scans++;
    run->raw_planes += obs.planes.size();
    run->raw_vertical += projected->ground.size();
    run->raw_other += projected->other_planes.size();
    run->skipped += projected->skipped;
    sc::Scan labelled;
    labelled.observation = k + 1;
    labelled.features = projected->ground;
    for (const auto& g : projected->ground) {
      labelled.truth.push_back(extracted.value()[g.id - first].label);
    }
    run->raw.push_back(std::move(labelled));
    t = std::chrono::steady_clock::now();
    MAPD_RETURN_IF_ERROR(walls.Add(k + 1, 1, projected->ground));
    run->wall_fusion_s += Since(t);
    MAPD_RETURN_IF_ERROR(planes.Add(k + 1, 1, projected->other_planes));
  }
  run->walls = walls.Published();
  run->planes = planes.Result();
  return Status::Ok();
}

void PrintRunHeader() {
  std::printf(
      "| world | scans | points per scan | raw planes (vertical / other) | fused walls | "
      "fused planes | simulation ms/scan | extraction ms/scan | wall fusion ms/scan | "
      "plane fusion ms/scan |\n|---|---:|---:|---|---:|---:|---:|---:|---:|---:|\n");
}

void PrintRun(const std::string& name, const Run& r) {
  const double n = std::max<size_t>(r.scans, 1);
  std::printf("| %s | %zu | %.0f | %zu (%zu / %zu) | %zu | %zu | %.1f | %.1f | %.2f | %.2f |\n",
              name.c_str(), r.scans, r.points / n, r.raw_planes, r.raw_vertical, r.raw_other,
              r.walls.size(), r.planes.fused.size(), 1e3 * r.sim_s / n, 1e3 * r.extract_s / n,
              1e3 * r.wall_fusion_s / n, 1e3 * r.planes.seconds / n);
}

// Distance from p to a fused wall's vertical strip (segment x [z_min, z_max]).
double WallDistance(const Eigen::Vector3d& p, const fusion::FusedFeature& w) {
  const double d = geometry::PointSegmentDistance(p.head<2>(), w.segment);
  const double dz = std::max({0.0, w.z_min_m - p.z(), p.z() - w.z_max_m});
  return std::hypot(d, dz);
}

double SegmentDistance3(const Eigen::Vector3d& p, const Eigen::Vector3d& a,
                        const Eigen::Vector3d& b) {
  const Eigen::Vector3d ab = b - a;
  const double t = std::clamp((p - a).dot(ab) / std::max(ab.squaredNorm(), 1e-12), 0.0, 1.0);
  return (a + t * ab - p).norm();
}

// Distance from p to a convex planar polygon.
double PolygonDistance(const Eigen::Vector3d& p, const FusedPlaneView& f) {
  const double h = f.normal.dot(p) + f.offset_m;
  const Eigen::Vector3d q = p - h * f.normal;  // p projected into the plane
  bool inside = f.boundary.size() >= 3;
  double edge = HUGE_VAL;
  int sign = 0;
  for (size_t i = 0; i < f.boundary.size(); ++i) {
    const Eigen::Vector3d& a = f.boundary[i];
    const Eigen::Vector3d& b = f.boundary[(i + 1) % f.boundary.size()];
    const double s = f.normal.dot((b - a).cross(q - a));
    const int sg = s > 0 ? 1 : (s < 0 ? -1 : 0);
    if (sg != 0 && sign != 0 && sg != sign) inside = false;
    if (sg != 0) sign = sg;
    edge = std::min(edge, SegmentDistance3(p, a, b));
  }
  return inside ? std::abs(h) : edge;
}

struct Coverage {
  size_t occupied = 0;
  size_t near_hit = 0;    // within 10 cm of a simulated scan point: what the scans saw
  size_t near_wall = 0;   // within 10 cm of a fused wall strip
  size_t near_plane = 0;  // within 10 cm of a fused non-vertical plane
  size_t near_fused = 0;  // either
  size_t near_both = 0;
};

Coverage MeasureCoverage(const octomap::OcTree& tree, const Run& r) {
  constexpr double kReach = 0.10;
  std::unordered_set<int64_t> hit_cells;  // 10 cm cells holding a scan point
  auto key = [](int64_t x, int64_t y, int64_t z) {
    return (x * 73856093) ^ (y * 19349663) ^ (z * 83492791);
  };
  for (const auto& h : r.hits) {
    hit_cells.insert(key(std::llround(std::floor(h.x() / kReach)),
                         std::llround(std::floor(h.y() / kReach)),
                         std::llround(std::floor(h.z() / kReach))));
  }
  Coverage c;
  for (auto it = tree.begin_leafs(), end = tree.end_leafs(); it != end; ++it) {
    if (!tree.isNodeOccupied(*it)) continue;
    const Eigen::Vector3d p(it.getX(), it.getY(), it.getZ());
    ++c.occupied;
    bool seen = false;
    const int64_t cx = std::llround(std::floor(p.x() / kReach)),
                  cy = std::llround(std::floor(p.y() / kReach)),
                  cz = std::llround(std::floor(p.z() / kReach));
    for (int dx = -1; dx <= 1 && !seen; ++dx)
      for (int dy = -1; dy <= 1 && !seen; ++dy)
        for (int dz = -1; dz <= 1 && !seen; ++dz)
          seen = hit_cells.count(key(cx + dx, cy + dy, cz + dz)) > 0;
    bool wall = false, plane = false;
    for (size_t i = 0; !wall && i < r.walls.size(); ++i)
      wall = WallDistance(p, r.walls[i]) <= kReach;
    for (size_t i = 0; !plane && i < r.planes.fused.size(); ++i) {
      plane = PolygonDistance(p, r.planes.fused[i]) <= kReach;
    }
    const bool fused = wall || plane;
    c.near_wall += wall;
    c.near_plane += plane;
    c.near_hit += seen;
    c.near_fused += fused;
    c.near_both += seen && fused;
  }
  return c;
}

std::string Colour(uint64_t id) {
  static const char* kPalette[] = {"#e41a1c", "#377eb8", "#4daf4a", "#984ea3",
                                   "#ff7f00", "#a65628", "#f781bf"};
  return kPalette[(id * 2654435761u) % 7];
}

// Top view: occupied voxels 0.3-1.8 m above the floor grey (by 0.2 m column,
// so the floor and the ceiling do not hide the walls), fused planes as light
// polygons, fused walls as coloured lines, sensor poses as black dots.
Status WriteTopView(const std::string& path, const std::string& title, const octomap::OcTree& tree,
                    const Run& r) {
  double x0, y0, z0, x1, y1, z1;
  tree.getMetricMin(x0, y0, z0);
  tree.getMetricMax(x1, y1, z1);
  const double s = 20.0, m = 10.0;  // px per metre, margin px
  std::ofstream out(path);
  if (!out) return Status::Unavailable("cannot write " + path);
  auto X = [&](double x) { return m + (x - x0) * s; };
  auto Y = [&](double y) { return m + 20 + (y1 - y) * s; };
  out << "<svg xmlns='http://www.w3.org/2000/svg' width='" << (x1 - x0) * s + 2 * m << "' height='"
      << (y1 - y0) * s + 2 * m + 20 << "'>\n<rect width='100%' height='100%' fill='white'/>\n"
      << "<text x='" << m << "' y='16' font-family='sans-serif' font-size='13'>" << title
      << "</text>\n";
  std::set<std::pair<int64_t, int64_t>> columns;
  const double floor_z = sim::EstimateFloorZ(tree);
  for (auto it = tree.begin_leafs(), end = tree.end_leafs(); it != end; ++it) {
    if (tree.isNodeOccupied(*it) && it.getZ() > floor_z + 0.3 && it.getZ() < floor_z + 1.8)
      columns.insert(
          {std::llround(std::floor(it.getX() / 0.2)), std::llround(std::floor(it.getY() / 0.2))});
  }
  out << "<g fill='#bbbbbb'>\n";
  for (const auto& [cx, cy] : columns) {
    out << "<rect x='" << X(cx * 0.2) << "' y='" << Y((cy + 1) * 0.2) << "' width='" << 0.2 * s
        << "' height='" << 0.2 * s << "'/>\n";
  }
  out << "</g>\n";
  for (const auto& f : r.planes.fused) {
    out << "<polygon fill='" << Colour(f.id) << "' fill-opacity='0.12' stroke='" << Colour(f.id)
        << "' stroke-dasharray='4 3' points='";
    for (const auto& b : f.boundary) out << X(b.x()) << ',' << Y(b.y()) << ' ';
    out << "'/>\n";
  }
  for (const auto& w : r.walls) {
    out << "<line x1='" << X(w.segment.a.x()) << "' y1='" << Y(w.segment.a.y()) << "' x2='"
        << X(w.segment.b.x()) << "' y2='" << Y(w.segment.b.y()) << "' stroke='" << Colour(w.id)
        << "' stroke-width='3'/>\n";
  }
  for (const auto& p : r.poses) {
    out << "<circle cx='" << X(p.translation.x()) << "' cy='" << Y(p.translation.y())
        << "' r='2'/>\n";
  }
  out << "</svg>\n";
  return out.good() ? Status::Ok() : Status::Unavailable("write failed: " + path);
}

int RealMaps(const std::string& data_dir, const std::string& docs_dir, bool write, size_t count) {
  std::printf("\n### Real buildings (OctoMap maps, %zu poses each)\n\n", count);
  PrintRunHeader();
  std::vector<std::string> coverage_rows, plane_rows;
  for (const std::string name : {"geb079", "fr_078_tidyup"}) {
    const std::string path = data_dir + "/" + name + ".bt";
    octomap::OcTree tree(0.1);
    if (!tree.readBinary(path)) {
      std::fprintf(stderr, "cannot read %s (pass --data DIR)\n", path.c_str());
      return 1;
    }
    sim::PoseSamplingParams sampling;
    sampling.count = count;
    const std::vector<Rigid3> poses = sim::SampleFreePoses(tree, sampling);
    const sim::OctoMapWorld world(tree);
    Run run;
    if (Status s = Drive(world, poses, true, &run); !s.ok()) {
      std::fprintf(stderr, "%s: %s\n", name.c_str(), s.ToString().c_str());
      return 1;
    }
    PrintRun(name + " (" + std::to_string(tree.getResolution()).substr(0, 4) + " m voxels)", run);
    for (const auto& f : run.planes.fused) {
      char text[256];
      std::snprintf(text, sizeof text, "| %s | %llu | (%.3f, %.3f, %.3f) | %.3f | %.1f | %u |\n",
                    name.c_str(), static_cast<unsigned long long>(f.id), f.normal.x(), f.normal.y(),
                    f.normal.z(), f.offset_m, f.area_m2, f.support);
      plane_rows.push_back(text);
    }
    const auto t = std::chrono::steady_clock::now();
    const Coverage c = MeasureCoverage(tree, run);
    char row[512];
    std::snprintf(row, sizeof row,
                  "| %s | %zu | %.1f %% | %.1f %% | %.1f %% | %.1f %% | %.1f %% | %.1f |\n",
                  name.c_str(), c.occupied, 100.0 * c.near_wall / c.occupied,
                  100.0 * c.near_plane / c.occupied, 100.0 * c.near_fused / c.occupied,
                  100.0 * c.near_hit / c.occupied,
                  100.0 * c.near_both / std::max<size_t>(c.near_hit, 1), Since(t));
    coverage_rows.push_back(row);
    if (write) {
      const std::string svg = docs_dir + "/planes-3d-" + name + ".svg";
      if (Status s =
              WriteTopView(svg, name + ": fused walls (lines) and planes (dashed)", tree, run);
          !s.ok()) {
        std::fprintf(stderr, "%s\n", s.ToString().c_str());
        return 1;
      }
    }
  }
  std::printf(
      "\nOccupied voxels (leaf centres) within 10 cm of a fused wall strip or fused plane:\n\n"
      "| map | occupied leaves | near a fused wall | near a fused plane | near either | "
      "near a scan point (seen) | seen ones near either | measured in (s) |\n"
      "|---|---:|---:|---:|---:|---:|---:|---:|\n");
  for (const auto& row : coverage_rows) std::printf("%s", row.c_str());
  if (!plane_rows.empty()) {
    std::printf(
        "\nFused non-vertical planes (map frame):\n\n| map | id | normal | offset (m) | "
        "area (m^2) | support |\n|---|---:|---|---:|---:|---:|\n");
    for (const auto& row : plane_rows) std::printf("%s", row.c_str());
  }
  return 0;
}

int City(const std::string& docs_dir, bool write, double step_m) {
  sc::ScenarioParams params;
  params.blocks_x = 4;
  params.blocks_y = 3;
  params.scan_spacing_m = step_m;
  const sc::World world = sc::GenerateWorld(params);
  // One ramp beside the road 20-30 m ahead of an early route pose, rising 1 m
  // over 10 m (5.7 deg: a MapPlane, not a wall), 1-5 m left of the road centre.
  const sc::Pose2& at = world.route[world.route.size() / 8];
  const Vec2 ahead(std::cos(at.yaw_rad), std::sin(at.yaw_rad));
  const Vec2 left(-ahead.y(), ahead.x());
  sim::Ramp ramp;
  ramp.start = at.t + 20.0 * ahead + 3.0 * left;
  ramp.end = ramp.start + 10.0 * ahead;
  const sim::CityWorld city(world, sim::CityHeights{}, {ramp});
  std::vector<Rigid3> poses;
  for (const sc::Pose2& p : world.route) {
    Rigid3 pose;
    pose.translation = {p.t.x(), p.t.y(), 1.8};
    pose.rotation = Eigen::Quaterniond(Eigen::AngleAxisd(p.yaw_rad, Eigen::Vector3d::UnitZ()));
    poses.push_back(pose);
  }
  Run run;
  if (Status s = Drive(city, poses, false, &run); !s.ok()) {
    std::fprintf(stderr, "city: %s\n", s.ToString().c_str());
    return 1;
  }
  std::printf(
      "\n### Synthetic city (%dx%d blocks, %zu buildings, %zu walls, a scan every %.1f m)\n\n",
      params.blocks_x, params.blocks_y, world.buildings.size(), world.wall_count, step_m);
  PrintRunHeader();
  PrintRun("city", run);
  const sc::MapMetrics q = sc::Evaluate(world, run.raw, run.walls, sc::MetricsParams());
  std::printf(
      "\n| fused walls | walls seen / matched | features per matched wall | on fences/poles | "
      "spurious | completeness | lateral RMS (cm) | corners met / evaluated | "
      "vertex error mean / median (cm) |\n|---:|---|---:|---:|---:|---:|---:|---|---|\n"
      "| %zu | %zu / %zu | %.2f | %zu | %zu | %.3f | %.2f | %zu / %zu | %.1f / %.1f |\n",
      q.fused, q.walls_seen, q.walls_matched, q.redundancy, q.on_trivial, q.spurious,
      q.completeness, 100.0 * q.lateral_rms_m, q.corners_met, q.corners_evaluated,
      100.0 * q.vertex_error_mean_m, 100.0 * q.vertex_error_median_m);
  std::printf("\nPlane fusion: %zu raw non-vertical planes, %zu kept as nodes at the end.\n",
              run.planes.raw, run.planes.nodes);
  const Eigen::Vector3d rn = ramp.normal();
  std::printf(
      "\nFused non-vertical planes (truth: the ground, normal (0, 0, 1), offset 0; "
      "the ramp, normal (%.3f, %.3f, %.3f), offset %.3f, 40 m^2):\n\n",
      rn.x(), rn.y(), rn.z(), ramp.offset());
  std::printf("| id | normal | offset (m) | area (m^2) | support |\n|---:|---|---:|---:|---:|\n");
  for (const auto& f : run.planes.fused) {
    std::printf("| %llu | (%.3f, %.3f, %.3f) | %.3f | %.0f | %u |\n",
                static_cast<unsigned long long>(f.id), f.normal.x(), f.normal.y(), f.normal.z(),
                f.offset_m, f.area_m2, f.support);
  }
  if (write) {
    sc::SvgPanel panel;
    panel.title = "city: fused walls from 16-beam LiDAR planes";
    for (const auto& w : run.walls) panel.segments.push_back(w.segment);
    const std::string svg = docs_dir + "/planes-3d-city.svg";
    if (Status s =
            sc::WriteSvg(svg, world, {panel}, world.min, world.min + Vec2(100.0, 100.0), 6.0);
        !s.ok()) {
      std::fprintf(stderr, "%s\n", s.ToString().c_str());
      return 1;
    }
  }
  return 0;
}

}  // namespace
}  // namespace mapd::bench

int main(int argc, char** argv) {
  const char* shared = std::getenv("MAPD_SHARED_DIR");
  std::string data_dir = shared != nullptr ? std::string(shared) + "/data/octomap" : "";
  std::string docs_dir = MAPD_SOURCE_DIR "/docs";
  bool write = true;
  size_t scans = 80;
  double step_m = 2.0;
  for (int i = 1; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--data") && i + 1 < argc) {
      data_dir = argv[++i];
    } else if (!std::strcmp(argv[i], "--docs") && i + 1 < argc) {
      docs_dir = argv[++i];
    } else if (!std::strcmp(argv[i], "--no-write")) {
      write = false;
    } else if (!std::strcmp(argv[i], "--scans") && i + 1 < argc) {
      scans = static_cast<size_t>(std::atol(argv[++i]));
    } else if (!std::strcmp(argv[i], "--city-step") && i + 1 < argc) {
      step_m = std::atof(argv[++i]);
    } else {
      std::fprintf(stderr,
                   "usage: %s [--data DIR] [--docs DIR] [--no-write] [--scans N] [--city-step M]\n",
                   argv[0]);
      return 2;
    }
  }
  if (scans < 1 || !(step_m >= 0.2)) {
    std::fprintf(stderr, "--scans must be >= 1 and --city-step >= 0.2 m\n");
    return 2;
  }
  if (data_dir.empty()) {
    std::fprintf(stderr,
                 "pass --data DIR (the folder of geb079.bt and fr_078_tidyup.bt) "
                 "or set MAPD_SHARED_DIR\n");
    return 2;
  }
  if (int rc = mapd::bench::City(docs_dir, write, step_m); rc != 0) return rc;
  return mapd::bench::RealMaps(data_dir, docs_dir, write, scans);
}
