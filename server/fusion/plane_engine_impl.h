// PlaneFusionEngine's internals, shared by plane_engine.cc (the algorithm) and
// plane_engine_state.cc (snapshots). Not part of the API: include plane_engine.h.
#ifndef MAPD_FUSION_PLANE_ENGINE_IMPL_H_
#define MAPD_FUSION_PLANE_ENGINE_IMPL_H_

#include <Eigen/Core>
#include <map>
#include <memory>
#include <unordered_map>
#include <vector>

#include "fusion/grid_index.h"
#include "fusion/plane_engine.h"
#include "fusion/plane_geometry.h"
#include "fusion/support_counter.h"

namespace mapd::fusion {

// Cell size of the ground grid planes are filed in. Floors are metres to tens
// of metres across: 2 m cells keep a room's floor in tens of cells.
constexpr double kPlaneCellM = 2.0;
// A plane whose ground projection (plus margin) covers more cells than this
// (a 128 m x 128 m floor) is not filed in the grid but kept on a list every
// query scans: a huge or absurd plane must not cost memory by its area.
constexpr int64_t kMaxCellsPerPlane = 4096;

// A raw plane kept as a node: what the criteria need.
struct PlaneNode {
  FeatureId id = 0;
  ObservationId observation = 0;
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();  // unit, CanonicalNormal sign
  double offset_m = 0.0;
  std::vector<Eigen::Vector3d> boundary;
  // Derived from the above (Prepare): not stored in snapshots.
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();  // mean of the boundary points
  double radius_m = 0.0;                               // farthest boundary point from it
  geometry::Vec2 ground_min = geometry::Vec2::Zero(), ground_max = geometry::Vec2::Zero();

  void Prepare();  // fills the derived fields
};

// Per cluster: enough to refit the fused plane after a merge without the members.
struct PlaneStats {
  ClusterId id = 0;
  uint32_t member_count = 0;
  uint64_t point_count = 0;  // boundary points of all members
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  Eigen::Matrix3d scatter = Eigen::Matrix3d::Zero();     // sum (p - mean)(p - mean)^T, m^2
  Eigen::Vector3d normal_sum = Eigen::Vector3d::Zero();  // member normals, sign-aligned
  // Member boundary points whose projections are the vertices of the fused
  // boundary, counter-clockwise about the fused normal.
  std::vector<Eigen::Vector3d> hull;
  SupportCounter observations;
  std::vector<RobotId> robots;  // distinct, ascending

  static PlaneStats OfNode(const PlaneNode& n, RobotId robot, uint32_t support_cap);
  // Absorbs `other` (left in an unspecified state) and refits the hull.
  void Merge(PlaneStats&& other, uint32_t support_cap);
  // The TLS plane of the boundary points: unit normal (CanonicalNormal sign), offset.
  void Fit(Eigen::Vector3d* normal, double* offset_m) const;
  FusedPlane ToFused() const;

 private:
  void RebuildHull(std::vector<Eigen::Vector3d> points);
};

class PlaneFusionEngine::Impl {
 public:
  explicit Impl(const PlaneFusionParams& params)
      : params_(params),
        support_cap_(std::max(kPlaneEstablishedSupport, params.min_support)),
        grid_(kPlaneCellM) {}

  Status Validate(const std::vector<MapPlane>& planes, std::vector<PlaneNode>* nodes) const;
  void Add(ObservationId observation, RobotId robot, std::vector<PlaneNode> nodes,
           PlaneChangeFeed* changes);
  bool Linked(const PlaneNode& a, const PlaneNode& b) const;
  // Whether `p` lies within the established cluster `s` (see plane_engine.h).
  bool Covered(const PlaneNode& p, const PlaneStats& s) const;
  uint32_t FindConst(uint32_t x) const;
  // Files node `i` under the cells of its ground projection (plus a margin).
  void FileInGrid(uint32_t i);
  // Recomputes published_ / root_of_id_ entries from the roots (snapshots).
  void RebuildDerived();

  const PlaneFusionParams params_;
  const uint32_t support_cap_;
  std::vector<PlaneNode> nodes_;
  std::vector<uint32_t> parent_;
  std::vector<uint32_t> size_;
  std::vector<std::unique_ptr<PlaneStats>> stats_;      // non-null at roots only
  std::unordered_map<ClusterId, uint32_t> root_of_id_;  // cluster id -> root node
  size_t cluster_count_ = 0;
  uint64_t plane_count_ = 0;
  UniformGrid<uint32_t> grid_;         // node indices, under every cell they cover
  std::vector<uint32_t> large_nodes_;  // nodes too large for the grid, ascending
  std::vector<uint64_t> visited_;      // per node: the query stamp that saw it last
  uint64_t stamp_ = 0;
  std::map<ClusterId, FusedPlane> published_;

 private:
  uint32_t Find(uint32_t x);
  uint32_t Union(uint32_t a, uint32_t b, std::vector<ClusterId>* merged_ids);
  double Margin(const PlaneNode& n) const;
};

}  // namespace mapd::fusion

#endif  // MAPD_FUSION_PLANE_ENGINE_IMPL_H_
