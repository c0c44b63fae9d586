// The incremental three-criteria fusion engine (docs/algorithms.md A.3-A.5).
//
// Features arrive observation by observation, already in the map frame and
// projected onto the ground plane (see projection.h). Each new feature is
// linked to earlier features of OTHER observations that meet all three
// criteria; clusters are the connected components of that graph (union-find).
// With the chain guard on (FusionParams::chain_max_rms_m > 0, chain_guard.h) a
// component that does not fit one line is published as the guard's groups, a
// function of its member set; "cluster" below then means such a group.
// In FusionMode::kExact the result is exactly what the batch algorithm gives
// on the same features, whatever the arrival order; cost and memory grow with
// every raw feature ever added.
//
// In FusionMode::kBounded (the default) a new feature whose endpoints lie
// within cover_m of an earlier representative of a cluster it meets the
// criteria with is folded into that representative: the cluster's statistics
// (moments, hull, support, robots) take it in, but later features are tested
// against the representatives only. On a revisited building the number of
// representatives saturates, so the cost of one observation depends on the
// walls around it, not on how often they were seen. The result depends on the
// arrival order (deterministically) and may differ from the exact one where a
// pair is borderline (docs/long-running.md measures by how much). The
// engine then does not remember every observation or feature id: the caller
// must not add an observation twice (mapd's ids come from the database).
//
// Thread safety: none. The caller serialises all calls (mapd calls it from its
// single writer thread).
#ifndef MAPD_FUSION_ENGINE_H_
#define MAPD_FUSION_ENGINE_H_

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "common/status.h"
#include "fusion/params.h"
#include "geometry/segment2.h"

namespace mapd::fusion {

using FeatureId = uint64_t;      // unique per raw feature, assigned by the caller
using ObservationId = uint64_t;  // unique per observation batch, assigned by the caller
using RobotId = uint64_t;
// A cluster is named by the smallest FeatureId among its members: stable while
// the cluster grows, and independent of arrival order.
using ClusterId = uint64_t;

enum class FeatureOrigin { kLine, kPlane };

// A raw feature in the map's ground plane.
struct GroundFeature {
  FeatureId id = 0;
  geometry::Segment2 segment;  // map frame, metres; non-zero length
  double z_min_m = 0.0;        // height range the feature spans (map frame)
  double z_max_m = 0.0;
  FeatureOrigin origin = FeatureOrigin::kLine;
};

// One fused feature: a cluster of raw features.
struct FusedFeature {
  ClusterId id = 0;
  geometry::Segment2 segment;  // after corner optimisation
  geometry::Segment2 fitted;   // total-least-squares fit, before corner optimisation
  double z_min_m = 0.0;
  double z_max_m = 0.0;
  uint32_t support = 0;         // distinct observations among the members
  uint32_t member_count = 0;    // raw features in the cluster
  uint32_t plane_members = 0;   // members that came from vertical planes (origin kPlane)
  std::vector<RobotId> robots;  // distinct contributing robots, ascending
};

// What one Add() changed in the published map (support >= min_support).
struct ChangeFeed {
  std::vector<ClusterId> added;    // newly published
  std::vector<ClusterId> updated;  // published before and after, geometry or support changed
  // Published before, gone now: merged into another cluster, or (chain guard)
  // no longer the smallest id of a group, or its group fell below min_support.
  std::vector<ClusterId> removed;
  bool empty() const { return added.empty() && updated.empty() && removed.empty(); }
};

class FusionEngine {
 public:
  // REQUIRES: params.Validate().ok() (use Create() to check).
  explicit FusionEngine(const FusionParams& params);
  ~FusionEngine();
  FusionEngine(FusionEngine&&) noexcept;
  FusionEngine& operator=(FusionEngine&&) noexcept;

  static StatusOr<std::unique_ptr<FusionEngine>> Create(const FusionParams& params);

  // Adds all features of one observation. All-or-nothing: a NaN or absurd
  // (|x| > 1e6 m) coordinate, a zero-length segment, a FeatureId used twice
  // in the batch, or (exact mode) a reused FeatureId or ObservationId is
  // refused with InvalidArgument and the engine is unchanged.
  // `changes`, if not null, receives what changed in the published map.
  Status Add(ObservationId observation, RobotId robot, const std::vector<GroundFeature>& features,
             ChangeFeed* changes = nullptr);
  // As Add, for an observation taken from sensor_xy_m (map frame, ground
  // plane): with FusionParams::wall_occluded_gap_m > 0 the space between the
  // sensor and each feature counts as observed free (free_space.h). A
  // non-finite or absurd origin is refused like a feature coordinate.
  Status AddFrom(ObservationId observation, RobotId robot, const geometry::Vec2& sensor_xy_m,
                 const std::vector<GroundFeature>& features, ChangeFeed* changes = nullptr);

  // Snapshots (bounded mode; Unimplemented in exact mode, whose restarts
  // replay): the whole state as bytes, and an engine restored from them that
  // gives the same results, bit for bit, for the same later input. LoadState
  // refuses bytes that are corrupt (checksum, bounds, structure) or were saved
  // with other parameters (FusionParamsKey) with a message saying which.
  Status SaveState(std::string* out) const;
  static StatusOr<std::unique_ptr<FusionEngine>> LoadState(const FusionParams& params,
                                                           std::string_view state);

  // Published fused features (support >= min_support), ascending by id.
  std::vector<FusedFeature> Published() const;
  // One cluster, published or not; nullopt if no such cluster. An unpublished
  // cluster of a component the chain guard regroups costs a regrouping
  // (tens of microseconds): writers of the published map use GetPublished.
  std::optional<FusedFeature> Get(ClusterId id) const;
  // One published feature (as in Published()); nullopt if `id` names none.
  // A map lookup.
  std::optional<FusedFeature> GetPublished(ClusterId id) const;

  size_t feature_count() const;  // raw features added
  // Union-find nodes: one per raw feature in exact mode, one per
  // representative in bounded mode (what memory and the work per feature
  // grow with).
  size_t node_count() const;
  size_t cluster_count() const;  // clusters (the guard's groups), published or not
  size_t published_count() const;
  // Published clusters retired because robots saw through them
  // (FusionParams::retire_views; wall_retirement.h): not in Published().
  size_t retired_count() const;
  // Those clusters, ascending by id (as fitted, before corner optimisation):
  // what the robots saw through. Not published; a view for operators and
  // benchmarks.
  std::vector<FusedFeature> Retired() const;
  // Nodes of the largest component ever formed (a component never shrinks).
  size_t largest_component_nodes() const;
  const FusionParams& params() const;

 private:
  // Read-only access to the raw cluster partition, for tests (engine_inspector.h).
  friend class EngineInspector;
  class Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace mapd::fusion

#endif  // MAPD_FUSION_ENGINE_H_
