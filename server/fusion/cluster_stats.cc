#include "fusion/cluster_stats.h"

#include <algorithm>
#include <iterator>
#include <utility>

#include "geometry/convex_hull2.h"

namespace mapd::fusion {

ClusterStats ClusterStats::OfFeature(const GroundFeature& f, ObservationId observation,
                                     RobotId robot) {
  ClusterStats s;
  s.id = f.id;
  s.member_count = 1;
  s.plane_members = f.origin == FeatureOrigin::kPlane ? 1 : 0;
  s.moments.Add(f.segment.a);
  s.moments.Add(f.segment.b);
  s.hull = {f.segment.a, f.segment.b};
  s.z_min_m = f.z_min_m;
  s.z_max_m = f.z_max_m;
  s.observations.Add(observation, SupportCounter::kUnlimited);
  s.robots = {robot};
  return s;
}

void ClusterStats::AddFeature(const GroundFeature& f, ObservationId observation, RobotId robot,
                              uint32_t support_cap, bool inside_hull) {
  id = std::min(id, f.id);
  ++member_count;
  plane_members += f.origin == FeatureOrigin::kPlane ? 1 : 0;
  moments.Add(f.segment.a);
  moments.Add(f.segment.b);
  z_min_m = std::min(z_min_m, f.z_min_m);
  z_max_m = std::max(z_max_m, f.z_max_m);
  // A revisited wall's new member usually lies inside the hull already.
  if (!inside_hull && (!geometry::StrictlyInsideHull(hull, f.segment.a) ||
                       !geometry::StrictlyInsideHull(hull, f.segment.b))) {
    std::vector<geometry::Vec2> points;
    points.reserve(hull.size() + 2);
    points.insert(points.end(), hull.begin(), hull.end());
    points.push_back(f.segment.a);
    points.push_back(f.segment.b);
    hull = geometry::ConvexHull(std::move(points));
  }
  observations.Add(observation, support_cap);
  auto it = std::lower_bound(robots.begin(), robots.end(), robot);
  if (it == robots.end() || *it != robot) robots.insert(it, robot);
}

template <typename Stats>
void ClusterStats::MergeAllButHull(Stats&& other, uint32_t support_cap) {
  id = std::min(id, other.id);
  member_count += other.member_count;
  plane_members += other.plane_members;
  moments.Merge(other.moments);
  z_min_m = std::min(z_min_m, other.z_min_m);
  z_max_m = std::max(z_max_m, other.z_max_m);

  observations.Merge(std::forward<Stats>(other).observations, support_cap);

  // The pieces of a wall were mostly seen by the same robots.
  if (std::includes(robots.begin(), robots.end(), other.robots.begin(), other.robots.end())) {
    return;
  }
  std::vector<RobotId> robots_union;
  robots_union.reserve(robots.size() + other.robots.size());
  std::set_union(robots.begin(), robots.end(), other.robots.begin(), other.robots.end(),
                 std::back_inserter(robots_union));
  robots = std::move(robots_union);
}

void ClusterStats::Merge(ClusterStats&& other, uint32_t support_cap) {
  // hull(A u B) = hull(hull(A) u hull(B)).
  std::vector<geometry::Vec2> points;
  points.reserve(hull.size() + other.hull.size());
  points.insert(points.end(), hull.begin(), hull.end());
  points.insert(points.end(), other.hull.begin(), other.hull.end());
  hull = geometry::ConvexHull(std::move(points));
  MergeAllButHull(std::move(other), support_cap);
}

ClusterStats ClusterStats::MergeAll(const std::vector<const ClusterStats*>& parts,
                                    uint32_t support_cap) {
  ClusterStats all = *parts.front();
  if (parts.size() == 1) return all;
  size_t vertices = 0;
  for (const ClusterStats* part : parts) vertices += part->hull.size();
  std::vector<geometry::Vec2> points;
  points.reserve(vertices);
  for (const ClusterStats* part : parts) {
    points.insert(points.end(), part->hull.begin(), part->hull.end());
  }
  // The others merged from where they are: a wall merges its pieces on every
  // refit, and copying each piece first was a fifth of the fuser's
  // allocations (city soak).
  for (size_t i = 1; i < parts.size(); ++i) all.MergeAllButHull(*parts[i], support_cap);
  // hull(A u B u ...) = hull(hull(A) u hull(B) u ...).
  all.hull = geometry::ConvexHull(std::move(points));
  return all;
}

ClusterStats::Fit ClusterStats::Refit() const {
  Fit fit;
  fit.line = geometry::FitLine(moments);
  fit.segment = geometry::ExtremeProjections(fit.line, hull);
  return fit;
}

FusedFeature ClusterStats::ToFused(const Fit& fit) const {
  FusedFeature f;
  f.id = id;
  f.segment = fit.segment;
  f.fitted = fit.segment;
  f.z_min_m = z_min_m;
  f.z_max_m = z_max_m;
  f.support = support();
  f.member_count = member_count;
  f.plane_members = plane_members;
  f.robots = robots;
  return f;
}

}  // namespace mapd::fusion
