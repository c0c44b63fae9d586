// Fusion of non-vertical planes (floors, ceilings, ramps): the planes that
// projection.h keeps apart (ProjectedObservation::other_planes), in the map
// frame. docs/fusion.md, "Non-vertical planes".
//
// Two raw planes of DIFFERENT observations are linked when all three
// criteria hold:
//   1. their unit normals make an angle <= max_normal_angle_rad (the sign of
//      a normal does not matter);
//   2. the centroid of each one's boundary lies within max_offset_m of the
//      other's plane;
//   3. their boundaries, projected into the common plane (normal: the mean of
//      the two, sign-aligned) as convex polygons, overlap or come within
//      max_gap_m of each other, and if min_overlap > 0, the intersection
//      covers at least min_overlap of the smaller polygon's area.
// Clusters are the connected components of that graph (union-find). A fused
// plane is the total-least-squares plane of all member boundary points, each
// point weighing the same (not area-weighted: boundaries are convex hulls or
// inlier outlines whose vertex count does not grow with the patch size), and
// its boundary the convex hull of the members' boundaries projected onto it.
//
// Bounded memory (like FusionMode::kBounded of the line engine, engine.h): a
// new plane that links to one cluster only, which at least
// kPlaneEstablishedSupport observations saw, and that lies inside that
// cluster's fused boundary (within cover_m) and within max_offset_m of its
// fused plane, is folded into the cluster's statistics and not kept as a node
// of its own. On a revisited building the nodes saturate, so the cost of one
// Add depends on the planes around it, not on the length of history; the
// candidate search is a ground grid (planes are filed under the cells of
// their ground projection). Below that support every plane stays a node, so
// the result on small sets does not depend on the arrival order (up to
// floating-point rounding of the sums). Deterministic in all cases.
//
// Thread safety: none. The caller serialises all calls.
#ifndef MAPD_FUSION_PLANE_ENGINE_H_
#define MAPD_FUSION_PLANE_ENGINE_H_

#include <Eigen/Core>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "common/status.h"
#include "fusion/engine.h"
#include "fusion/projection.h"

namespace mapd::fusion {

struct PlaneFusionParams {
  double max_normal_angle_rad = 5.0 * 3.14159265358979323846 / 180.0;  // criterion 1
  double max_offset_m = 0.10;  // criterion 2: centroid-to-other-plane distance, metres
  // Criterion 3: min overlap, as the intersection's share of the smaller
  // projected boundary's area, in [0, 1]; 0 = any overlap or a gap up to max_gap_m.
  double min_overlap = 0.0;
  double max_gap_m = 0.3;    // criterion 3: max gap between projected boundaries, metres
  uint32_t min_support = 3;  // distinct observations a fused plane needs to be published
  // Folding (see above): a plane within this of an established cluster's
  // fused boundary is folded into it, metres.
  double cover_m = 0.05;

  // InvalidArgument naming the offending field.
  Status Validate() const;
};

// Every parameter as text, doubles to 17 digits (snapshots are only loaded
// with the same text).
std::string PlaneFusionParamsKey(const PlaneFusionParams& params);

// Support (distinct observations) from which a cluster folds covered planes.
constexpr uint32_t kPlaneEstablishedSupport = 32;

struct FusedPlane {
  ClusterId id = 0;                                   // smallest member FeatureId
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();  // unit, map frame, CanonicalNormal sign
  double offset_m = 0.0;                              // normal.dot(x) + offset_m = 0
  // Convex hull of the member boundaries projected onto the fused plane,
  // counter-clockwise about `normal`, map frame, metres.
  std::vector<Eigen::Vector3d> boundary;
  double area_m2 = 0.0;  // of `boundary`
  double z_min_m = 0.0;  // height range of `boundary`
  double z_max_m = 0.0;
  uint32_t support = 0;         // distinct observations among the members
  uint32_t member_count = 0;    // raw planes, folded ones included
  std::vector<RobotId> robots;  // ascending
};

// What one Add() changed among the published planes (support >= min_support);
// same meaning as for lines.
using PlaneChangeFeed = ChangeFeed;

class PlaneFusionEngine {
 public:
  // REQUIRES: params.Validate().ok() (use Create() to check).
  explicit PlaneFusionEngine(const PlaneFusionParams& params);
  ~PlaneFusionEngine();
  PlaneFusionEngine(PlaneFusionEngine&&) noexcept;
  PlaneFusionEngine& operator=(PlaneFusionEngine&&) noexcept;

  static StatusOr<std::unique_ptr<PlaneFusionEngine>> Create(const PlaneFusionParams& params);

  // Adds the planes of one observation (map frame). All-or-nothing: a
  // non-finite or absurd (|x| > 1e6 m) value, a normal not of unit length
  // (within 1e-3; it is renormalised), fewer than 3 boundary points, or a
  // FeatureId used twice in the batch is refused with InvalidArgument naming
  // "planes[i]", and the engine is unchanged. The caller must not add an
  // observation twice.
  Status Add(ObservationId observation, RobotId robot, const std::vector<MapPlane>& planes,
             PlaneChangeFeed* changes = nullptr);

  // Published planes (support >= min_support), ascending by id.
  std::vector<FusedPlane> Published() const;
  // One cluster, published or not; nullopt if no such cluster.
  std::optional<FusedPlane> Get(ClusterId id) const;

  size_t plane_count() const;    // raw planes added, folded ones included
  size_t node_count() const;     // planes kept as nodes (what the work per Add scans)
  size_t cluster_count() const;  // published or not
  size_t published_count() const;
  const PlaneFusionParams& params() const;

  // The whole state as bytes, and an engine restored from them that gives
  // the same results, bit for bit, for the same later input. LoadState
  // refuses corrupt bytes (checksum, bounds, structure) and bytes saved with
  // other parameters, with a message saying which.
  Status SaveState(std::string* out) const;
  static StatusOr<std::unique_ptr<PlaneFusionEngine>> LoadState(const PlaneFusionParams& params,
                                                                std::string_view state);

 private:
  class Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace mapd::fusion

#endif  // MAPD_FUSION_PLANE_ENGINE_H_
