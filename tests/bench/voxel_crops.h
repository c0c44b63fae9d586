// Two overlapping crops of a real voxel map, the second moved by a random rigid
// transform: the trials of the real-map merge benchmark (voxel_merge_bench).
//
// Crops are slabs along the map's longest horizontal axis (x or y, by the extent
// of the occupied voxels): every occupied voxel whose key along that axis lies in
// the slab's key range, over the map's whole extent in the other two axes.
// Overlap is defined on occupied voxels: |A n B| / min(|A|, |B|), the share of
// the smaller crop's occupied voxels that are also in the other crop. Both crops
// get the same number of occupied voxels n = min(max_occupied_per_crop,
// N / (2 - overlap)) (N = the map's occupied voxels), so a map larger than two
// crops is cropped to fit and the pair's window slides along the axis with the
// seed. Slab edges fall between key layers, so the achieved overlap is within a
// layer of the requested one: it is measured and reported.
//
// Negative pairs (disjoint = true): two slabs of n = min(max_occupied_per_crop,
// 0.4 N) occupied voxels each with no key layer in common and at least gap_m
// between them along the axis, so no merge of them is right.
//
// Re-voxelisation (both crops, A with the identity, so that they are treated
// alike): nearest-neighbour resampling. A target voxel takes the state of the
// source voxel that contains T^-1(target centre), restricted to the crop's slab;
// every target voxel in the box that the moved slab can reach is visited. So
// occupied surfaces have no holes from the rotation, and the crop carries ALL of
// the source map's free space inside the slab (its ray-cast free leaves, not
// only free voxels next to surfaces), as a real submap's OctoMap would: the
// overlap score's "B lands on space A saw as free" needs it.
//
// Deterministic: the same map, parameters and seed give the same bytes.
#ifndef MAPD_TESTS_BENCH_VOXEL_CROPS_H_
#define MAPD_TESTS_BENCH_VOXEL_CROPS_H_

#include <Eigen/Geometry>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>

#include "common/status.h"
#include "voxel/voxel_grid.h"

namespace mapd::bench {

struct CropParams {
  double overlap = 0.5;   // requested |A n B| / min(|A|, |B|), in (0, 1); unused if disjoint
  bool disjoint = false;  // a negative pair: no shared voxel, gap_m apart (see above)
  double gap_m = 2.0;     // smallest distance between disjoint slabs, metres
  std::size_t max_occupied_per_crop = 150'000;
  double max_tilt_deg = 10.0;       // roll and pitch uniform in [-max, max]
  double max_translation_m = 20.0;  // translation uniform in a ball of this radius
  std::uint64_t seed = 1;

  Status Validate() const;
};

struct CropPair {
  std::string a_bt;  // crop A, in the map's frame, as an OctoMap .bt file
  std::string b_bt;  // crop B, moved: p_B = T_B_map * p_map
  // Ground truth: maps B's coordinates into A's (= the map's) frame.
  Eigen::Isometry3d T_a_b = Eigen::Isometry3d::Identity();
  Eigen::Vector3d centroid_b = Eigen::Vector3d::Zero();  // of B's occupied voxels, B frame, metres
  int axis = 0;                                          // 0 = x, 1 = y: the slab axis
  std::size_t occupied_a = 0;                            // source voxels in crop A
  std::size_t occupied_b = 0;                            // source voxels in crop B
  std::size_t shared = 0;                                // source voxels in both
  double achieved_overlap = 0.0;                         // shared / min(occupied_a, occupied_b)
  std::size_t out_occupied_a = 0, out_occupied_b = 0;    // after re-voxelisation
  std::size_t out_free_a = 0, out_free_b = 0;
  double yaw_deg = 0, roll_deg = 0, pitch_deg = 0, translation_m = 0;  // the drawn motion
};

// InvalidArgument for bad params (the field is named), FailedPrecondition for a
// map with too few occupied voxels (< 1000) to cut two crops.
StatusOr<CropPair> MakeCropPair(const voxel::VoxelGrid& map, const CropParams& params);

// The seed of one benchmark trial: depends on the map's file name (no
// directory), the overlap and the trial index, not on the order of the maps or
// overlaps in a run, so that a run of one map or one method, and the
// diagnostic tool, draw the same trials.
std::uint64_t TrialSeed(std::uint64_t base_seed, const std::string& map_file_name, double overlap,
                        int trial);

// Errors of an estimate against the truth. The translation error is measured
// where it matters: the distance between est * c and truth * c for the centroid
// c of crop B (metres), so a frame origin far from the data does not turn a
// small rotation error into a large translation error.
double RotationErrorDeg(const Eigen::Isometry3d& est, const Eigen::Isometry3d& truth);
double TranslationErrorAt(const Eigen::Isometry3d& est, const Eigen::Isometry3d& truth,
                          const Eigen::Vector3d& point);

// An OctoMap .bt file's bytes, or the file at `path`, as a voxel grid (the
// errors of voxel::ReadOctree and VoxelGrid::FromOcTree).
StatusOr<voxel::VoxelGrid> GridFromBytes(const std::string& bt_bytes);
StatusOr<voxel::VoxelGrid> ReadGridFile(const std::string& path);

// Trial `trial` of voxel_merge_bench run with its default flags (--seed=1,
// --gap-m=2, --max-voxels=150000) on the map file `map_path` (its name,
// without the directory, seeds it); overlap <= 0 gives the negative pair.
// The crops are read back from their .bt bytes, as the merge reads them.
// The diagnostics replay the benchmark's trials with it.
struct BenchTrial {
  CropPair pair;
  voxel::VoxelGrid a, b;
};
StatusOr<BenchTrial> MakeBenchTrial(const voxel::VoxelGrid& map, const std::string& map_path,
                                    double overlap, int trial);
// Reads the map at `map_path` and calls `visit` with trials [first, first +
// count) of MakeBenchTrial; a trial that cannot be made is reported on stdout
// and skipped. Returns 2 (after reporting on stderr) when the map cannot be
// read, else 0: the diagnostics' main loop.
int ForEachBenchTrial(const std::string& map_path, double overlap, int first, int count,
                      const std::function<void(int trial, const BenchTrial&)>& visit);

}  // namespace mapd::bench

#endif  // MAPD_TESTS_BENCH_VOXEL_CROPS_H_
