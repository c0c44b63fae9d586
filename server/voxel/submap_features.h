// What the pair stages of a merge need of one submap beyond its voxels: its
// corners (docs/algorithms.md B.1-B.3) and its gravity frame (B.9). Each is
// computed on first use and kept for every pair the submap is in, so a merge
// that the correlation generator settles never extracts corners, and a
// submap in several pairs is levelled once. Also its overlap and ICP
// indexes. Internal to merge*.cc.
#ifndef MAPD_VOXEL_SUBMAP_FEATURES_H_
#define MAPD_VOXEL_SUBMAP_FEATURES_H_

#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>

#include "common/status.h"
#include "voxel/corner.h"
#include "voxel/icp.h"
#include "voxel/merge.h"
#include "voxel/merge_overlap.h"
#include "voxel/normals_grid.h"
#include "voxel/voxel_grid.h"

namespace mapd::voxel {

class SubmapFeatures {
 public:
  // `grid` and `params` must outlive this.
  SubmapFeatures(uint64_t id, const VoxelGrid* grid, const MergeParams* params)
      : id_(id), grid_(grid), params_(params) {}

  // The corners; the first call extracts them and adds its seconds to
  // times->corners_s. Errors: ExtractCorners's (bad params, a map beyond its
  // limits), naming the submap.
  StatusOr<const CornerSet*> Corners(StageTimes* times);
  // Whether Corners() was called since StartMerge() (a prepared submap
  // keeps its corners from merge to merge; a merge reports only those it used).
  bool corners_used() const { return corners_used_; }
  void StartMerge() { corners_used_ = false; }

  // The levelling and wall histogram; the first call computes them and adds
  // its seconds to times->correlation_s. FailedPrecondition (kept) when the
  // map has no floor, ceiling or wall plane: the generator cannot run on it.
  const StatusOr<GravityFrame>& Gravity(StageTimes* times);

  // The occupied voxels' index and normals at kGravityNormalRadiusVoxels,
  // shared by levelling and (at that radius) corner extraction.
  const internal::GridSurface& Surface();

  // This submap as the A of overlap scores (merge_overlap.h), built on first use.
  const OverlapIndex& Overlap();

  // The occupied voxel centres as ICP's target with their index at
  // `voxel_size_m` (the merge's finest resolution), built on first use (again
  // if asked at another size).
  const IcpTarget& IcpIndex(double voxel_size_m);

  // The mean of the occupied voxel centres, metres (zero for an empty grid):
  // where two transforms of this submap are compared (DistinctTransforms).
  const Eigen::Vector3d& OccupiedCentroid();

  // Heap bytes of what has been computed so far, approximately
  // (voxel/memory_bytes.h).
  std::size_t MemoryBytes() const;

 private:
  uint64_t id_;
  const VoxelGrid* grid_;
  const MergeParams* params_;
  std::optional<CornerSet> corners_;
  bool corners_used_ = false;
  std::optional<StatusOr<GravityFrame>> gravity_;
  std::optional<internal::GridSurface> surface_;
  std::optional<OverlapIndex> overlap_;
  std::optional<Eigen::Vector3d> centroid_;
  std::unique_ptr<IcpTarget> icp_target_;
};

}  // namespace mapd::voxel

#endif  // MAPD_VOXEL_SUBMAP_FEATURES_H_
