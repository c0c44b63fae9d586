// Point-to-point ICP on occupied voxel centres (docs/algorithms.md B.5: the
// refinement of the corner transform on the occupied voxel centres of the
// overlap).
//
// Besl & McKay 1992 with two robustifications: correspondences farther than
// max_correspondence_voxels are ignored, and of the rest only the closest
// trim_fraction are used (trimmed ICP, Chetverikov et al. 2002), so the
// non-overlapping part of the source does not pull the fit. Each iteration
// solves the rigid fit in closed form (Umeyama 1991 eq. (39)-(42), c = 1).
// Point-to-point: no normals to estimate on one-voxel-thick rasterised walls.
// Its linear convergence is the price: on geb079.bt (8 cm voxels) from 1 deg
// and 7 cm off it reaches 0.02 deg / 3 mm and stops by the RMS criterion
// after 18 iterations (point-to-plane would need fewer; not done).
//
// Nearest neighbours, exact within max_correspondence_voxels: the target
// points binned into cells of one voxel (NearestVoxelIndex, nearest_voxel.h:
// bit sets and rank, a hash only for huge boxes); a query scans rings of
// cells outwards and stops as soon as the best distance is below the next
// ring's bound (usually after the 27 cells around it). It replaced PCL's
// KdTreeFLANN, with the same results and faster (geb079.bt, 186k voxels,
// 10k source points: 0.42 vs 0.67 CPU s a RefineIcp; fr_078_tidyup.bt 0.79
// vs 0.92), and with it the server's last use of PCL.
// Between iterations a source point keeps its target without a search while
// it provably stays the nearest (reuse_pairings; exact): on the benchmark's
// crops 35-63 % of the searches of a merge's ICP runs, and 7-13 % of an
// fr_078_tidyup merge's CPU (docs/archive/voxel-merge-history.md, "Kept ICP pairings").
// Pure function; thread compatible.
#ifndef MAPD_VOXEL_ICP_H_
#define MAPD_VOXEL_ICP_H_

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstddef>
#include <memory>
#include <vector>

#include "common/status.h"
#include "voxel/nearest_voxel.h"

namespace mapd::voxel {

// Distances in voxels (multiples of `voxel_size_m` given to RefineIcp).
struct IcpParams {
  int max_iterations = 50;
  // Pairs farther apart than this are not correspondences.
  double max_correspondence_voxels = 3.0;
  // Of the pairs within max_correspondence_voxels, the closest fraction is
  // used. Default 1 (no trimming): the distance gate already drops the
  // non-overlapping part, and on geb079.bt trimming 10% halved the speed of
  // convergence (the largest residuals carry most of the correction).
  double trim_fraction = 1.0;
  // Converged when one iteration changes the rotation by less than this
  // (radians) and the translation by less than this (voxels).
  double convergence_rotation_rad = 1e-4;
  double convergence_translation_voxels = 1e-2;
  // ... or when the RMS of the used pairs changes by less than this fraction
  // (trimming on a voxel grid can make the pose jitter below a voxel forever).
  double convergence_rms_relative = 1e-4;
  // Source points used (an even, deterministic subsample of the overlap);
  // 0 = all. A few ten thousand fix a rigid transform far below a voxel.
  std::size_t max_source_points = 10'000;
  // Keep a source point's pairing without a search while its
  // image has provably not moved closer to another target (icp.cc,
  // StillNearest). Exact: the same pairs, so the same result bit for bit
  // (tested); off only to measure it.
  bool reuse_pairings = true;
  // Fewer inliers than this in an iteration: FailedPrecondition.
  int min_inliers = 10;

  // InvalidArgument naming the first bad field.
  Status Validate() const;
};

struct IcpResult {
  Eigen::Isometry3d T_target_source = Eigen::Isometry3d::Identity();
  double rms_residual_m = 0.0;  // RMS distance of the final inliers, metres
  int inliers = 0;              // correspondences used in the final evaluation
  int iterations = 0;
  bool converged = false;         // the last step was below the convergence thresholds
  std::size_t source_points = 0;  // source points in the overlap (after subsampling)
  std::size_t target_points = 0;  // target points in the k-d tree
  // Neighbour searches run, over all iterations (fewer than source_points x
  // (iterations + 1) when reuse_pairings kept pairings).
  std::size_t searches = 0;
};

// A target point set with its NearestVoxelIndex, built once for many RefineIcp
// calls against one map: a merge refines a dozen or more hypotheses against
// the same submap, and building the index in every call was 2-5 % of a merge
// (docs/voxel-merge.md). Each call still pairs only with the target points
// of its own overlap (the index is asked within a box), so its result is the
// vector overload's, bit for bit.
class IcpTarget {
 public:
  // `points` must outlive this. A voxel size that is not finite and > 0, or
  // non-finite points, leave no index: every RefineIcp call with this target
  // then returns InvalidArgument, as the vector overload would.
  IcpTarget(const std::vector<Eigen::Vector3d>* points, double voxel_size_m);
  ~IcpTarget();
  IcpTarget(const IcpTarget&) = delete;
  IcpTarget& operator=(const IcpTarget&) = delete;

  const std::vector<Eigen::Vector3d>& points() const { return *points_; }
  double voxel_size_m() const { return voxel_size_m_; }
  // Heap bytes of its index, approximately.
  std::size_t MemoryBytes() const { return index_ == nullptr ? 0 : index_->MemoryBytes(); }
  // Ok, or why no index was built.
  const Status& status() const { return status_; }
  // REQUIRES: status().ok().
  const NearestVoxelIndex& index() const { return *index_; }

 private:
  const std::vector<Eigen::Vector3d>* points_;
  double voxel_size_m_;
  Status status_;
  std::unique_ptr<NearestVoxelIndex> index_;
};

// Refines T_target_source, starting from T_init. Only the overlap takes part:
// source points whose initial image lies within the target's bounding box
// grown by half a voxel (source points beyond a cut end of the target would
// pull the fit), target points within the source's transformed bounding box
// grown by max_correspondence_voxels. Errors: InvalidArgument for bad
// params, a voxel size that is not finite and > 0, or non-finite input;
// FailedPrecondition when the overlap has fewer than min_inliers pairs.
StatusOr<IcpResult> RefineIcp(const std::vector<Eigen::Vector3d>& target,
                              const std::vector<Eigen::Vector3d>& source,
                              const Eigen::Isometry3d& T_init, double voxel_size_m,
                              const IcpParams& params = {});

// The same against a target indexed once (voxel size: the target's).
StatusOr<IcpResult> RefineIcp(const IcpTarget& target, const std::vector<Eigen::Vector3d>& source,
                              const Eigen::Isometry3d& T_init, const IcpParams& params = {});

// RefineIcp's residual at T without refining it: the same overlap (judged
// from T), subsample, correspondences and RMS as its final evaluation, with
// iterations 0 and converged true. For comparing given transforms on equal
// terms (voxel/lattice_pose.h).
StatusOr<IcpResult> EvaluateIcp(const IcpTarget& target, const std::vector<Eigen::Vector3d>& source,
                                const Eigen::Isometry3d& T, const IcpParams& params = {});

}  // namespace mapd::voxel

#endif  // MAPD_VOXEL_ICP_H_
