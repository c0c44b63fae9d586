// Corner extraction on the real OctoMap maps (the paper's Table 1 figures):
// occupied voxels, window candidates, verified candidates, corners, a
// "locally consistent" count, seconds per stage, and repeatability under
// random rigid motions.
//
// Usage: voxel_corners_bench [key=value ...] [octomap_dir]
//   (default dir $MAPD_SHARED_DIR/data/octomap, else /work/shared/data/octomap)
//   CornerExtractionParams overrides: tau rms smooth curv eps nrad search band
//   support fradius refine det maxplanes dist minregion offset cluster scale rangle
//   repeat=N   N random rigid motions per map (yaw any, roll/pitch <= 10 deg,
//              translation <= 20 m): the occupied centres are moved and
//              re-voxelised at the same resolution, corners are extracted
//              again and mapped back; a corner of the original repeats when a
//              moved corner lies within 2 voxels of it.
//   maps=a.bt,b.bt  only these maps.
//
// "Consistent" corner (our objective rule, no hand labels exist): an occupied
// voxel within 1 voxel of the corner, and each of its three faces, taken as
// the occupied voxels within 5 voxels of the corner that are within 1 voxel
// of that face's plane and not of the other two, has >= 10 voxels, a local
// least-squares plane with RMS <= 0.5 voxel, and the three local planes meet
// within 1 voxel of the reported corner.
#include <Eigen/Dense>
#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "voxel/corner_extraction.h"
#include "voxel/octree_reader.h"
#include "voxel/voxel_grid.h"

namespace {

using mapd::voxel::Corner;
using mapd::voxel::CornerExtractionParams;
using mapd::voxel::CornerExtractionResult;
using mapd::voxel::CornerSet;
using mapd::voxel::VoxelGrid;
using mapd::voxel::VoxelKey;

double Since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

bool SetParam(const std::string& key, double v, CornerExtractionParams* p) {
  if (key == "tau")
    p->tau_change = static_cast<int>(v);
  else if (key == "rms")
    p->max_plane_rms = v;
  else if (key == "smooth")
    p->smoothness_deg = v;
  else if (key == "curv")
    p->curvature_threshold = v;
  else if (key == "eps")
    p->plane_epsilon = v;
  else if (key == "nrad")
    p->normal_radius = v;
  else if (key == "search")
    p->plane_search_radius = v;
  else if (key == "band")
    p->face_band = v;
  else if (key == "support")
    p->min_face_support = static_cast<int>(v);
  else if (key == "fradius")
    p->face_support_radius = v;
  else if (key == "refine")
    p->refine_iterations = static_cast<int>(v);
  else if (key == "det")
    p->min_normal_determinant = v;
  else if (key == "maxplanes")
    p->max_planes_per_candidate = static_cast<int>(v);
  else if (key == "dist")
    p->max_region_plane_distance = v;
  else if (key == "minregion")
    p->min_region_size = static_cast<int>(v);
  else if (key == "offset")
    p->max_corner_offset = v;
  else if (key == "cluster")
    p->cluster_radius = v;
  else if (key == "rangle")
    p->region_angle_deg = v;
  else if (key == "scale")
    p->scale = static_cast<int>(v);
  else
    return false;
  return true;
}

// The rule in the header comment. Voxel units inside.
bool Consistent(const VoxelGrid& grid, const Corner& corner) {
  const double res = grid.resolution();
  const Eigen::Vector3d x = corner.position / res;
  const VoxelKey c = grid.PointToKey(corner.position);
  bool occupied_near = false;
  std::array<std::vector<Eigen::Vector3d>, 3> faces;
  for (int dx = -6; dx <= 6; ++dx) {
    for (int dy = -6; dy <= 6; ++dy) {
      for (int dz = -6; dz <= 6; ++dz) {
        const VoxelKey k = c + VoxelKey(dx, dy, dz);
        if (!grid.IsOccupied(k)) continue;
        const Eigen::Vector3d p = k.cast<double>() + Eigen::Vector3d::Constant(0.5);
        const double r = (p - x).norm();
        if (r <= 1.0) occupied_near = true;
        if (r > 5.0) continue;
        int face = -1;
        for (int f = 0; f < 3; ++f) {
          if (std::abs(corner.normals[f].dot(p - x)) > 1.0) continue;
          face = face == -1 ? f : 3;
        }
        if (face >= 0 && face < 3) faces[face].push_back(p);
      }
    }
  }
  if (!occupied_near) return false;
  Eigen::Matrix3d n;
  Eigen::Vector3d d;
  for (int f = 0; f < 3; ++f) {
    if (faces[f].size() < 10) return false;
    Eigen::Vector3d mean = Eigen::Vector3d::Zero();
    for (const auto& p : faces[f]) mean += p;
    mean /= static_cast<double>(faces[f].size());
    Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
    for (const auto& p : faces[f]) cov += (p - mean) * (p - mean).transpose();
    cov /= static_cast<double>(faces[f].size());
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(cov);
    if (std::sqrt(std::max(0.0, eigen.eigenvalues()(0))) > 0.5) return false;
    n.row(f) = eigen.eigenvectors().col(0).transpose();
    d(f) = n.row(f).dot(mean);
  }
  if (std::abs(n.determinant()) < 0.1) return false;
  const Eigen::Vector3d y = n.colPivHouseholderQr().solve(d);
  return (y - x).norm() <= 1.0;
}

// A random rigid motion as the merge tests use: any yaw, roll/pitch <= 10 deg,
// translation <= 20 m per axis.
Eigen::Isometry3d RandomMotion(std::mt19937& rng) {
  std::uniform_real_distribution<double> yaw(-M_PI, M_PI), tilt(-10.0, 10.0), shift(-20.0, 20.0);
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.linear() = (Eigen::AngleAxisd(yaw(rng), Eigen::Vector3d::UnitZ()) *
                Eigen::AngleAxisd(tilt(rng) * M_PI / 180.0, Eigen::Vector3d::UnitY()) *
                Eigen::AngleAxisd(tilt(rng) * M_PI / 180.0, Eigen::Vector3d::UnitX()))
                   .toRotationMatrix();
  t.translation() = Eigen::Vector3d(shift(rng), shift(rng), shift(rng));
  return t;
}

mapd::StatusOr<VoxelGrid> Moved(const VoxelGrid& grid, const Eigen::Isometry3d& t) {
  std::vector<VoxelKey> keys;
  keys.reserve(grid.num_occupied());
  for (const Eigen::Vector3d& c : grid.occupied_centres()) keys.push_back(grid.PointToKey(t * c));
  return VoxelGrid::FromKeys(grid.resolution(), keys);
}

// Corners of `a` with a corner of `b` (mapped back by t_inv) within 2 voxels.
int Repeated(const CornerSet& a, const CornerSet& b, const Eigen::Isometry3d& t_inv, double res,
             const std::vector<bool>* only) {
  int count = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    if (only != nullptr && !(*only)[i]) continue;
    for (const Corner& c : b) {
      if ((t_inv * c.position - a[i].position).norm() <= 2.0 * res) {
        ++count;
        break;
      }
    }
  }
  return count;
}

}  // namespace

int main(int argc, char** argv) {
  using namespace mapd::voxel;
  const char* shared = std::getenv("MAPD_SHARED_DIR");
  CornerExtractionParams params;
  int repeat = 0;
  std::vector<std::string> maps = {"geb079.bt", "fr_078_tidyup.bt", "new_college.bt"};
  std::string dir = std::string(shared != nullptr ? shared : "/work/shared") + "/data/octomap";
  for (int arg = 1; arg < argc; ++arg) {
    const std::string a = argv[arg];
    const auto eq = a.find('=');
    if (eq == std::string::npos) {
      dir = a;
      continue;
    }
    const std::string key = a.substr(0, eq), value = a.substr(eq + 1);
    if (key == "repeat") {
      repeat = std::atoi(value.c_str());
    } else if (key == "maps") {
      maps.clear();
      std::stringstream ss(value);
      for (std::string m; std::getline(ss, m, ',');) maps.push_back(m);
    } else if (!SetParam(key, std::atof(value.c_str()), &params)) {
      std::fprintf(stderr, "unknown option %s\n", key.c_str());
      return 2;
    }
  }
  std::printf(
      "| map | res m | occupied voxels | scale | working voxels | candidates (B.1) | triples | "
      "verified (B.2) |"
      " clusters (B.3) | corners | consistent | planes | read s | grid s | window s |"
      " normals s | planes s | verify s | cluster s | total s | total CPU s |\n"
      "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
  int failures = 0;
  std::vector<std::string> repeat_rows;
  for (const std::string& name : maps) {
    auto start = std::chrono::steady_clock::now();
    mapd::StatusOr<OcTreePtr> tree = ReadOctreeFile(dir + "/" + name);
    const double read_s = Since(start);
    if (!tree.ok()) {
      std::printf("| %s | %s |\n", name.c_str(), tree.status().ToString().c_str());
      ++failures;
      continue;
    }
    start = std::chrono::steady_clock::now();
    mapd::StatusOr<VoxelGrid> grid = VoxelGrid::FromOcTree(**tree);
    const double grid_s = Since(start);
    if (!grid.ok()) {
      std::printf("| %s | %s |\n", name.c_str(), grid.status().ToString().c_str());
      ++failures;
      continue;
    }
    start = std::chrono::steady_clock::now();
    const std::clock_t cpu_start = std::clock();
    mapd::StatusOr<CornerExtractionResult> r = ExtractCorners(*grid, params);
    const double total_s = Since(start);
    // Process CPU seconds: on a shared, loaded machine wall time overstates.
    const double cpu_s = static_cast<double>(std::clock() - cpu_start) / CLOCKS_PER_SEC;
    if (!r.ok()) {
      std::printf("| %s | %s |\n", name.c_str(), r.status().ToString().c_str());
      ++failures;
      continue;
    }
    std::vector<bool> consistent;
    for (const Corner& c : r->corners) consistent.push_back(Consistent(*grid, c));
    const auto num_consistent = std::count(consistent.begin(), consistent.end(), true);
    std::printf(
        "| %s | %.2f | %zu | %d | %zu | %zu | %zu | %zu | %zu | %zu | %ld | %zu | %.2f | %.2f | "
        "%.2f |"
        " %.2f | %.2f | %.2f | %.2f | %.2f | %.2f |\n",
        name.c_str(), grid->resolution(), r->occupied_voxels, r->scale, r->working_voxels,
        r->candidates, r->triples, r->verified_candidates, r->clusters, r->corners.size(),
        static_cast<long>(num_consistent), r->planes, read_s, grid_s, r->seconds_window,
        r->seconds_normals, r->seconds_planes, r->seconds_verify, r->seconds_cluster, total_s,
        cpu_s);
    std::fflush(stdout);

    std::mt19937 rng(7);
    for (int trial = 0; trial < repeat; ++trial) {
      const Eigen::Isometry3d t = RandomMotion(rng);
      mapd::StatusOr<VoxelGrid> moved = Moved(*grid, t);
      if (!moved.ok()) {
        ++failures;
        continue;
      }
      start = std::chrono::steady_clock::now();
      mapd::StatusOr<CornerExtractionResult> m = ExtractCorners(*moved, params);
      const double moved_s = Since(start);
      if (!m.ok()) {
        ++failures;
        continue;
      }
      const Eigen::Isometry3d t_inv = t.inverse();
      const int rep = Repeated(r->corners, m->corners, t_inv, grid->resolution(), nullptr);
      const int rep_consistent =
          Repeated(r->corners, m->corners, t_inv, grid->resolution(), &consistent);
      std::fprintf(stderr, "  within 1/2/3/4 voxels:");
      for (double k : {1.0, 2.0, 3.0, 4.0}) {
        int c = 0;
        for (const Corner& a : r->corners) {
          for (const Corner& b : m->corners) {
            if ((t_inv * b.position - a.position).norm() <= k * grid->resolution()) {
              ++c;
              break;
            }
          }
        }
        std::fprintf(stderr, " %d", c);
      }
      std::fprintf(stderr, "\n");
      // Chance level: the same count after a wrong shift of (7, 5, 3) voxels.
      Eigen::Isometry3d wrong = t_inv;
      wrong.pretranslate(Eigen::Vector3d(7, 5, 3) * grid->resolution());
      const int chance = Repeated(r->corners, m->corners, wrong, grid->resolution(), nullptr);
      for (std::size_t k : {25, 50, 100}) {
        const CornerSet ta(r->corners.begin(), r->corners.begin() + std::min(k, r->corners.size()));
        const CornerSet tb(m->corners.begin(), m->corners.begin() + std::min(k, m->corners.size()));
        std::fprintf(stderr, "  top %zu: %d repeat within 2 voxels\n", k,
                     Repeated(ta, tb, t_inv, grid->resolution(), nullptr));
      }
      const Eigen::AngleAxisd aa(t.linear());
      char row[512];
      std::snprintf(
          row, sizeof(row),
          "| %s | %d | %.0f deg | %zu | %zu | %d (%.0f %%) | %d | %d / %ld | %.2f "
          "(%.2f %.2f %.2f %.2f %.2f) |",
          name.c_str(), trial, aa.angle() * 180.0 / M_PI, r->corners.size(), m->corners.size(), rep,
          r->corners.empty() ? 0.0 : 100.0 * rep / static_cast<double>(r->corners.size()), chance,
          rep_consistent, static_cast<long>(num_consistent), moved_s, m->seconds_window,
          m->seconds_normals, m->seconds_planes, m->seconds_verify, m->seconds_cluster);
      repeat_rows.push_back(row);
      std::fprintf(stderr, "%s\n", row);
    }
  }
  if (!repeat_rows.empty()) {
    std::printf(
        "\n| map | trial | rotation | corners | corners (moved) | repeated within 2 voxels |"
        " chance (wrong shift) | consistent repeated |"
        " moved extraction s (window normals planes verify cluster) |\n"
        "|---|---|---|---|---|---|---|---|---|\n");
    for (const std::string& row : repeat_rows) std::printf("%s\n", row.c_str());
  }
  return failures == 0 ? 0 : 1;
}
