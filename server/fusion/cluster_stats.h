// What the engine keeps per cluster: enough to refit the fused feature of
// docs/algorithms.md A.7 after a merge without revisiting the members.
#ifndef MAPD_FUSION_CLUSTER_STATS_H_
#define MAPD_FUSION_CLUSTER_STATS_H_

#include <cstdint>
#include <vector>

#include "fusion/engine.h"
#include "fusion/support_counter.h"
#include "geometry/line_fit.h"

namespace mapd::fusion {

struct ClusterStats {
  ClusterId id = 0;  // smallest member FeatureId
  uint32_t member_count = 0;
  uint32_t plane_members = 0;        // members projected from vertical planes
  geometry::PointMoments2 moments;   // of all member endpoints
  std::vector<geometry::Vec2> hull;  // convex hull of all member endpoints
  double z_min_m = 0.0;
  double z_max_m = 0.0;
  SupportCounter observations;  // distinct observations: the support
  std::vector<RobotId> robots;  // distinct, ascending

  static ClusterStats OfFeature(const GroundFeature& f, ObservationId observation, RobotId robot);

  // Absorbs `other` (which is left in an unspecified state). Costs
  // O(support) for the observation ids while exact (support_counter.h; `cap`
  // bounds them) and O(h log h) for the hulls, h = number of hull vertices.
  void Merge(ClusterStats&& other, uint32_t support_cap);
  // The stats of the union of parts (at least one), merged in their order,
  // as Merge would, with one hull of all their hulls' vertices at the end
  // rather than one per part (a wall of k pieces: one sort, not k - 1).
  static ClusterStats MergeAll(const std::vector<const ClusterStats*>& parts, uint32_t support_cap);
  // Absorbs one more member: Merge(OfFeature(f, observation, robot)), cheaper.
  // `inside_hull`: the caller knows both endpoints lie strictly inside the
  // hull (the hull is then left as it is without a test).
  void AddFeature(const GroundFeature& f, ObservationId observation, RobotId robot,
                  uint32_t support_cap, bool inside_hull = false);

  uint32_t support() const { return observations.count(); }

  // The total-least-squares fit of the member endpoints and the segment of its
  // extreme projections (paper section 3.2, Figure 6).
  struct Fit {
    geometry::Line2 line;
    geometry::Segment2 segment;
  };
  Fit Refit() const;

  // The fused feature before corner optimisation (segment == fitted).
  FusedFeature ToFused(const Fit& fit) const;

 private:
  // Merge without the hull; from a const ClusterStats& it copies nothing
  // but what it keeps.
  template <typename Stats>
  void MergeAllButHull(Stats&& other, uint32_t support_cap);
};

}  // namespace mapd::fusion

#endif  // MAPD_FUSION_CLUSTER_STATS_H_
