// Corner optimisation of the published fused features (paper section 3.2,
// Figure 7; docs/algorithms.md A.8, "Corner optimisation").
//
// The rule, chosen to be a function of the published set alone (so independent
// of arrival order) and local (so the engine recomputes only near a change):
//  - E is the set of fitted endpoints of all published features.
//  - N(e) is the endpoint e' of ANOTHER feature nearest to e with |e - e'| < snap_m;
//    ties go to the smaller (cluster id, end index), end 0 = fitted.a, 1 = fitted.b.
//  - e and e' snap iff N(e) = e' and N(e') = e (mutual nearest neighbours), so
//    every endpoint snaps at most once. Three walls meeting at one point: only
//    the mutual pair snaps. If both endpoints of a feature pair with the two
//    endpoints of one other feature, neither snaps: that is no corner but two
//    views of one short stretch, which snapping would make identical.
//  - The joint point is their midpoint (CornerMode::kMidpoint, the paper), or the
//    intersection of the two fitted lines (kIntersection) when they cross at more
//    than kMinCornerAngleRad and the intersection lies within snap_m of both
//    endpoints; otherwise (kIntersection) each endpoint moves along its own
//    fitted line to the foot of the midpoint. A joint off a wall's line tilts
//    the whole wall: a midpoint up to snap_m / 2 off it drew a 7 m corridor
//    wall of the ACES log 13 cm into the corridor, on space the laser saw
//    through (issue 40); the two ends then meet within their lines' distance.
// The result for e depends only on endpoints within 2 * snap_m of e (N(e) is
// within snap_m, and N(N(e)) within snap_m of that).
//
// CornerPairing::kGreedy instead pairs the plain way (the paper names no rule:
// "if the distance between two endpoints is within a certain threshold"):
// features in ascending id, each endpoint (a, then b) not yet paired takes the
// nearest endpoint not yet paired of ANOTHER feature with |e - e'| < snap_m (ties
// as above); both go to the joint point; the twin rule above applies too. Still a
// function of the published set, but not local in a fixed radius: the pairing of
// e depends on its connected component in the graph "endpoints of different
// features closer than snap_m" (greedy in a global order, restricted to a
// component, is greedy on it); a feature's result, on its two ends' components.
// docs/fusion.md, "Corner pairing", compares the two against ground truth.
#ifndef MAPD_FUSION_CORNER_SNAP_H_
#define MAPD_FUSION_CORNER_SNAP_H_

#include <map>
#include <unordered_map>
#include <utility>
#include <vector>

#include "fusion/engine.h"
#include "fusion/grid_index.h"
#include "fusion/params.h"
#include "geometry/line_fit.h"

namespace mapd::fusion {

// Lines crossing at less than this are "near-parallel": their intersection is
// ill-conditioned, so the corner falls back to the midpoint.
constexpr double kMinCornerAngleRad = 10.0 * 3.14159265358979323846 / 180.0;

// The joint of endpoint p (of line lp) and q (of line lq): the point both
// move to, and whether it lies on both lines (the intersection). Symmetric
// bit for bit when the caller passes the pair in a fixed order.
struct CornerJoint {
  geometry::Vec2 point;
  bool intersection = false;
};
CornerJoint CornerPoint(const geometry::Vec2& p, const geometry::Line2& lp, const geometry::Vec2& q,
                        const geometry::Line2& lq, double snap_m, CornerMode mode);

class CornerSnapper {
 public:
  CornerSnapper(double snap_m, CornerMode mode,
                CornerPairing pairing = CornerPairing::kMutualNearest);

  // Adds or replaces published feature `id`.
  void Upsert(ClusterId id, const geometry::Segment2& fitted, const geometry::Line2& line);
  void Erase(ClusterId id);

  // Appends the ids of published features with an endpoint within radius_m of p.
  void CollectNear(const geometry::Vec2& p, double radius_m, std::vector<ClusterId>* ids) const;

  // The fitted segment and line of published feature `id`; false if absent.
  bool Lookup(ClusterId id, geometry::Segment2* fitted, geometry::Line2* line) const;

  // Appends the ids of published features whose snapped segment may change when
  // endpoints appear, move or vanish at `points` (their old and new positions):
  // mutual, those with an endpoint within 2 * snap_m + slack_m of a point; greedy,
  // those with an endpoint in the component of an endpoint within snap_m + slack_m.
  void CollectAffected(const std::vector<geometry::Vec2>& points, double slack_m,
                       std::vector<ClusterId>* ids) const;

  // The corner-optimised segments of published features `ids`, in that order
  // (greedy: each component solved once). REQUIRES: every id is present.
  std::vector<geometry::Segment2> SnappedAll(const std::vector<ClusterId>& ids) const;
  geometry::Segment2 Snapped(ClusterId id) const { return SnappedAll({id})[0]; }

  double snap_m() const { return snap_m_; }

 private:
  struct Entry {
    geometry::Segment2 fitted;
    geometry::Line2 line;
  };
  struct EndRef {
    ClusterId id;
    int end;  // 0 = a, 1 = b
    geometry::Vec2 p;
  };
  using EndKey = std::pair<ClusterId, int>;  // (id, end): the order of greedy
  // Nearest endpoint of another feature within snap_m, among those `skip`
  // does not reject; false if none.
  template <typename Skip>
  bool Nearest(ClusterId id, const geometry::Vec2& p, Skip skip, EndRef* nearest) const;
  // Greedy: the endpoints of the component of `seed`, in (id, end) order.
  std::vector<EndRef> Component(const EndRef& seed) const;
  // Greedy on one component: the partner of each endpoint paired, into *partner.
  void SolveGreedy(const std::vector<EndRef>& component, std::map<EndKey, EndRef>* partner) const;
  geometry::Vec2 Joint(const EndRef& e, const EndRef& other) const;
  static const geometry::Vec2& EndOf(const Entry& e, int end) {
    return end == 0 ? e.fitted.a : e.fitted.b;
  }

  double snap_m_;
  CornerMode mode_;
  CornerPairing pairing_;
  std::unordered_map<ClusterId, Entry> entries_;
  UniformGrid<EndRef> grid_;
};

}  // namespace mapd::fusion

#endif  // MAPD_FUSION_CORNER_SNAP_H_
