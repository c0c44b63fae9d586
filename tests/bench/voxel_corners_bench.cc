// Corner extraction on the real OctoMap maps (the paper's Table 1 figures):
// occupied voxels, window candidates, verified candidates, clusters, corners,
// and seconds per stage. Usage: voxel_corners_bench [octomap_dir]
// (default $MAPD_SHARED_DIR/data/octomap, else /work/shared/data/octomap)
// [tau=N] [rms=X] [smooth=DEG] [curv=X] [eps=X]: CornerExtractionParams overrides.
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "voxel/corner_extraction.h"
#include "voxel/octree_reader.h"
#include "voxel/voxel_grid.h"

namespace {

double Since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace

int main(int argc, char** argv) {
  using namespace mapd::voxel;
  const char* shared = std::getenv("MAPD_SHARED_DIR");
  CornerExtractionParams params;
  int arg = 1;
  for (; arg < argc && std::string(argv[arg]).find('=') != std::string::npos; ++arg) {
    const std::string a = argv[arg];
    const std::string key = a.substr(0, a.find('='));
    const double v = std::atof(a.c_str() + a.find('=') + 1);
    if (key == "tau") params.tau_change = static_cast<int>(v);
    if (key == "rms") params.max_plane_rms = v;
    if (key == "smooth") params.smoothness_deg = v;
    if (key == "curv") params.curvature_threshold = v;
    if (key == "eps") params.plane_epsilon = v;
  }
  const std::string dir = argc > arg ? argv[arg]
                                   : std::string(shared != nullptr ? shared : "/work/shared") +
                                         "/data/octomap";
  std::printf("| map | res m | occupied voxels | candidates (B.1) | verified (B.2) | clusters (B.3) |"
              " corners | planes | SVT blocks | read s | grid s | window s | planes s | verify s |"
              " cluster s |\n|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
  int failures = 0;
  for (const char* name : {"geb079.bt", "fr_078_tidyup.bt", "new_college.bt"}) {
    auto start = std::chrono::steady_clock::now();
    mapd::StatusOr<OcTreePtr> tree = ReadOctreeFile(dir + "/" + name);
    const double read_s = Since(start);
    if (!tree.ok()) {
      std::printf("| %s | %s |\n", name, tree.status().ToString().c_str());
      ++failures;
      continue;
    }
    start = std::chrono::steady_clock::now();
    mapd::StatusOr<VoxelGrid> grid = VoxelGrid::FromOcTree(**tree);
    const double grid_s = Since(start);
    if (!grid.ok()) {
      std::printf("| %s | %s |\n", name, grid.status().ToString().c_str());
      ++failures;
      continue;
    }
    mapd::StatusOr<CornerExtractionResult> r = ExtractCorners(*grid, params);
    if (!r.ok()) {
      std::printf("| %s | %s |\n", name, r.status().ToString().c_str());
      ++failures;
      continue;
    }
    std::printf("| %s | %.2f | %zu | %zu | %zu | %zu | %zu | %zu | %zu | %.2f | %.2f | %.2f | %.2f |"
                " %.2f | %.2f |\n",
                name, grid->resolution(), r->occupied_voxels, r->candidates, r->verified_candidates,
                r->clusters, r->corners.size(), r->planes, r->table_blocks, read_s, grid_s,
                r->seconds_window, r->seconds_planes, r->seconds_verify, r->seconds_cluster);
    std::fflush(stdout);
  }
  return failures == 0 ? 0 : 1;
}
