#include "fusion/batch_reference.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <functional>
#include <map>
#include <queue>
#include <set>
#include <utility>

#include "fusion/criteria.h"
#include "fusion/wall_consolidation.h"

namespace mapd::fusion::testing {
namespace {

using geometry::Segment2;
using geometry::Vec2;

struct Flat {
  GroundFeature feature;
  ObservationId observation;
};

struct Fit {
  Vec2 point;
  Vec2 direction;
};

Fit FitEndpoints(const std::vector<Vec2>& points) {
  Vec2 mean = Vec2::Zero();
  for (const Vec2& p : points) mean += p;
  mean /= static_cast<double>(points.size());
  Eigen::Matrix2d scatter = Eigen::Matrix2d::Zero();
  for (const Vec2& p : points) scatter += (p - mean) * (p - mean).transpose();
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eig(scatter);
  return {mean, eig.eigenvectors().col(1).normalized()};  // largest eigenvalue last
}

Vec2 Joint(const Vec2& p, const Fit& lp, const Vec2& q, const Fit& lq, const FusionParams& params) {
  const Vec2 mid = (p + q) / 2.0;
  if (params.corner_mode == CornerMode::kMidpoint) return mid;
  // Without a usable intersection, p slides along its own line to the point
  // nearest the midpoint.
  const Vec2 foot = lp.point + (mid - lp.point).dot(lp.direction) * lp.direction;
  const double angle = std::acos(std::min(1.0, std::abs(lp.direction.dot(lq.direction))));
  if (angle <= 10.0 * 3.14159265358979323846 / 180.0) return foot;
  // lp.point + t * lp.direction = lq.point + s * lq.direction
  Eigen::Matrix2d a;
  a.col(0) = lp.direction;
  a.col(1) = -lq.direction;
  const Eigen::Vector2d ts = a.colPivHouseholderQr().solve(lq.point - lp.point);
  const Vec2 x = lp.point + ts(0) * lp.direction;
  if ((x - p).norm() > params.snap_m || (x - q).norm() > params.snap_m) return foot;
  return x;
}

// Sum of squared orthogonal distances of `points` to their TLS line: the
// smaller eigenvalue of the scatter about the mean.
double Sse(const std::vector<Vec2>& points) {
  Vec2 mean = Vec2::Zero();
  for (const Vec2& p : points) mean += p;
  mean /= static_cast<double>(points.size());
  Eigen::Matrix2d scatter = Eigen::Matrix2d::Zero();
  for (const Vec2& p : points) scatter += (p - mean) * (p - mean).transpose();
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eig(scatter);
  return eig.eigenvalues()(0);  // ascending
}

// What the guard cuts: a raw feature, or (consolidation) a published cluster
// standing for all its members' endpoints, ordered by its own midpoint.
struct Unit {
  uint64_t id;
  Vec2 key_point;
  std::vector<Vec2> points;
  std::vector<ObservationId> observations;  // empty: publishable in any subset
};

bool Publishable(const std::vector<Unit>& units, const std::vector<size_t>& members,
                 const FusionParams& params) {
  std::set<ObservationId> seen;
  bool any = false;
  for (size_t i : members) {
    any |= !units[i].observations.empty();
    seen.insert(units[i].observations.begin(), units[i].observations.end());
  }
  return !any || seen.size() >= params.min_support;
}

std::vector<Vec2> PointsOf(const std::vector<Unit>& units, const std::vector<size_t>& members) {
  std::vector<Vec2> points;
  for (size_t i : members)
    points.insert(points.end(), units[i].points.begin(), units[i].points.end());
  return points;
}

// The chain guard's rule (fusion/chain_guard.h), literally and recursively:
// appends the groups of `members` (indices into `units`) to `groups`.
using CutAllowed =
    std::function<bool(const std::vector<size_t>& head, const std::vector<size_t>& tail)>;

void GuardGroups(const std::vector<Unit>& units, const std::vector<size_t>& members,
                 const FusionParams& params, const CutAllowed& cut_allowed,
                 std::vector<std::vector<size_t>>* groups) {
  const std::vector<Vec2> points = PointsOf(units, members);
  const double sse = Sse(points);
  const double rms = std::sqrt(std::max(0.0, sse) / static_cast<double>(points.size()));
  if (params.chain_max_rms_m == 0.0 || members.size() < 2 || rms <= params.chain_max_rms_m) {
    groups->push_back(members);
    return;
  }
  // Order along the fitted direction, its sign fixed by the reference
  // direction at 0.3 rad; ties by id.
  Fit fit = FitEndpoints(points);
  if (fit.direction.dot(Vec2(std::cos(0.3), std::sin(0.3))) < 0.0) fit.direction = -fit.direction;
  std::vector<size_t> order = members;
  const auto key = [&](size_t i) { return (units[i].key_point - fit.point).dot(fit.direction); };
  std::sort(order.begin(), order.end(), [&](size_t x, size_t y) {
    if (key(x) != key(y)) return key(x) < key(y);
    return units[x].id < units[y].id;
  });
  // The cheapest cut below the ratio whose both sides are publishable.
  size_t best_k = 0;
  double best_cost = 0.0;
  for (size_t k = 1; k < order.size(); ++k) {
    const std::vector<size_t> head(order.begin(), order.begin() + static_cast<long>(k));
    const std::vector<size_t> tail(order.begin() + static_cast<long>(k), order.end());
    const double cost =
        std::max(0.0, Sse(PointsOf(units, head))) + std::max(0.0, Sse(PointsOf(units, tail)));
    if (!(cost < params.chain_max_sse_ratio * sse)) continue;
    if (!cut_allowed(head, tail)) continue;
    if (best_k == 0 || cost < best_cost) {
      best_k = k;
      best_cost = cost;
    }
  }
  if (best_k == 0) {
    groups->push_back(members);
    return;
  }
  GuardGroups(units, std::vector<size_t>(order.begin(), order.begin() + static_cast<long>(best_k)),
              params, cut_allowed, groups);
  GuardGroups(units, std::vector<size_t>(order.begin() + static_cast<long>(best_k), order.end()),
              params, cut_allowed, groups);
}

// The fitted segment of `endpoints`: their TLS line, cut at the extreme projections.
Segment2 FittedSegment(const std::vector<Vec2>& endpoints, Fit* fit) {
  *fit = FitEndpoints(endpoints);
  double t_min = 1e300, t_max = -1e300;
  for (const Vec2& p : endpoints) {
    t_min = std::min(t_min, (p - fit->point).dot(fit->direction));
    t_max = std::max(t_max, (p - fit->point).dot(fit->direction));
  }
  return {fit->point + t_min * fit->direction, fit->point + t_max * fit->direction};
}

// Connected components of the symmetric relation `linked` over 0 .. n-1, by BFS.
template <typename Linked>
std::vector<std::vector<size_t>> Components(size_t n, Linked linked) {
  std::vector<std::vector<size_t>> out;
  std::vector<bool> seen(n, false);
  for (size_t start = 0; start < n; ++start) {
    if (seen[start]) continue;
    std::vector<size_t> component;
    std::queue<size_t> queue;
    queue.push(start);
    seen[start] = true;
    while (!queue.empty()) {
      const size_t i = queue.front();
      queue.pop();
      component.push_back(i);
      for (size_t j = 0; j < n; ++j) {
        if (!seen[j] && linked(i, j)) {
          seen[j] = true;
          queue.push(j);
        }
      }
    }
    std::sort(component.begin(), component.end());
    out.push_back(std::move(component));
  }
  return out;
}

// Free-space evidence, from docs/algorithms.md A.11 ("Free-space evidence"):
// a cell of 0.25 m is seen free when at least wall_free_min_count visibility
// triangles (sensor, a, b) contain its centre in their interior eroded by
// 0.005 m per metre of range from both rays and 0.4 m from the segment.
class SeenFree {
 public:
  static constexpr double kCellM = 0.25;
  static constexpr double kRayErosionPerM = 0.005;  // times the range along the ray
  static constexpr double kSegmentErosionM = 0.4;
  // Samples along a line at most this far apart (docs: "every 0.125 m").
  static constexpr double kSampleStepM = 0.125;

  SeenFree(const std::vector<BatchObservation>& observations, uint32_t min_count)
      : min_count_(min_count) {
    for (const BatchObservation& o : observations) {
      if (!o.has_sensor) continue;
      for (const GroundFeature& f : o.features) Count(o.sensor_xy_m, f.segment.a, f.segment.b);
    }
  }

  bool IsFree(const Vec2& p) const {
    const auto it = counts_.find({Cell(p.x()), Cell(p.y())});
    return it != counts_.end() && it->second >= min_count_;
  }
  size_t free_cells() const {
    size_t n = 0;
    for (const auto& [cell, count] : counts_) n += count >= min_count_;
    return n;
  }
  // Whether any point from p + t0 u to p + t1 u, sampled at most kSampleStepM
  // apart with both ends included, lies in a seen-free cell.
  bool AnyFree(const Vec2& p, const Vec2& u, double t0, double t1) const {
    const int steps = std::max(1, static_cast<int>(std::ceil((t1 - t0) / kSampleStepM)));
    for (int i = 0; i <= steps; ++i) {
      if (IsFree(p + (t0 + (t1 - t0) * i / steps) * u)) return true;
    }
    return false;
  }

 private:
  static int64_t Cell(double x) { return static_cast<int64_t>(std::floor(x / kCellM)); }
  // Signed distance of p from the line x -> y, positive on its left.
  static double Left(const Vec2& x, const Vec2& y, const Vec2& p) {
    return geometry::Cross(y - x, p - x) / (y - x).norm();
  }
  void Count(const Vec2& o, Vec2 a, Vec2 b) {
    const double twice_area = geometry::Cross(a - o, b - o);
    if (twice_area == 0.0) return;          // no interior
    if (twice_area < 0.0) std::swap(a, b);  // counter-clockwise: the interior is on the left
    const auto inside = [&](const Vec2& p) {
      const auto range = [&](const Vec2& end) { return (end - o).normalized().dot(p - o); };
      return Left(o, a, p) >= kRayErosionPerM * range(a) && Left(a, b, p) >= kSegmentErosionM &&
             Left(b, o, p) >= kRayErosionPerM * range(b);
    };
    for (int64_t cx = Cell(std::min({o.x(), a.x(), b.x()}));
         cx <= Cell(std::max({o.x(), a.x(), b.x()})); ++cx) {
      for (int64_t cy = Cell(std::min({o.y(), a.y(), b.y()}));
           cy <= Cell(std::max({o.y(), a.y(), b.y()})); ++cy) {
        if (inside(Vec2((cx + 0.5) * kCellM, (cy + 0.5) * kCellM))) ++counts_[{cx, cy}];
      }
    }
  }

  const uint32_t min_count_;
  std::map<std::pair<int64_t, int64_t>, uint32_t> counts_;
};

// Proofs of occlusion, from docs/algorithms.md A.11 ("Proof of occlusion"):
// in one observation, two features on one line (the longer one's, L: within
// delta, the shorter's ends within wall_offset_m of it) with a gap along L of
// more than wall_gap_m and at most wall_occluded_gap_m, seen from more than
// wall_offset_m off L's line, at most 4 apart in the order of their
// midpoints' bearings from the sensor: every other feature with a point
// strictly inside the triangle (sensor, the gap's ends moved wall_offset_m
// towards the sensor) proves occluded its shadow on L's line (where the rays
// through its ends meet it), within the gap. The cells of a proven stretch
// are those of its points every 0.0625 m, both ends included.
class ProvenOccluded {
 public:
  static constexpr double kCellM = 0.25;
  static constexpr double kMarkStepM = 0.0625;
  static constexpr double kSampleStepM = 0.125;

  ProvenOccluded(const std::vector<BatchObservation>& observations, const FusionParams& params) {
    for (const BatchObservation& o : observations) {
      if (!o.has_sensor) continue;
      const size_t n = o.features.size();
      std::vector<std::pair<double, size_t>> by_bearing;
      for (size_t i = 0; i < n; ++i) {
        const Vec2 m = o.features[i].segment.midpoint() - o.sensor_xy_m;
        by_bearing.push_back({std::atan2(m.y(), m.x()), i});
      }
      std::sort(by_bearing.begin(), by_bearing.end());
      for (size_t x = 0; x < n; ++x) {
        for (size_t y = x + 1; y < n && y <= x + 4; ++y) {
          Pair(o, by_bearing[x].second, by_bearing[y].second, params);
        }
      }
    }
  }

  bool Proven(const Vec2& p) const { return cells_.count({Cell(p.x()), Cell(p.y())}) != 0; }
  // Whether every sample from p + t0 u to p + t1 u (every kSampleStepM, both
  // ends included) is proven.
  bool AllProven(const Vec2& p, const Vec2& u, double t0, double t1) const {
    const int steps = std::max(1, static_cast<int>(std::ceil((t1 - t0) / kSampleStepM)));
    for (int i = 0; i <= steps; ++i) {
      if (!Proven(p + (t0 + (t1 - t0) * i / steps) * u)) return false;
    }
    return true;
  }

 private:
  static int64_t Cell(double x) { return static_cast<int64_t>(std::floor(x / kCellM)); }

  void Pair(const BatchObservation& o, size_t i, size_t j, const FusionParams& params) {
    const Segment2& p = o.features[i].segment;
    const Segment2& q = o.features[j].segment;
    const Segment2& l = p.length() >= q.length() ? p : q;
    const Segment2& s = p.length() >= q.length() ? q : p;
    const Vec2 u = l.direction().normalized();
    if (std::abs(geometry::Cross(u, s.direction().normalized())) > std::sin(params.delta_rad))
      return;
    const Vec2 n(-u.y(), u.x());
    if (std::abs(n.dot(s.a - l.a)) > params.wall_offset_m ||
        std::abs(n.dot(s.b - l.a)) > params.wall_offset_m) {
      return;
    }
    const double ta = u.dot(s.a - l.a), tb = u.dot(s.b - l.a);
    double t0, t1;
    if (std::min(ta, tb) > l.length()) {
      t0 = l.length();
      t1 = std::min(ta, tb);
    } else if (std::max(ta, tb) < 0.0) {
      t0 = std::max(ta, tb);
      t1 = 0.0;
    } else {
      return;
    }
    if (!(t1 - t0 > params.wall_gap_m) || t1 - t0 > params.wall_occluded_gap_m) return;
    const Vec2& o_xy = o.sensor_xy_m;
    const double side = n.dot(o_xy - l.a);
    if (!(std::abs(side) > params.wall_offset_m)) return;
    const Vec2 toward = (side > 0.0 ? 1.0 : -1.0) * params.wall_offset_m * n;
    const Vec2 g0 = l.a + t0 * u + toward, g1 = l.a + t1 * u + toward;
    for (size_t k = 0; k < o.features.size(); ++k) {
      if (k == i || k == j) continue;
      const Segment2& occluder = o.features[k].segment;
      if (!Inside(occluder, o_xy, g0, g1)) continue;
      double sa, sb;
      if (!Shadow(o_xy, occluder.a, l.a, u, &sa) || !Shadow(o_xy, occluder.b, l.a, u, &sb))
        continue;
      const double lo = std::max(t0, std::min(sa, sb)), hi = std::min(t1, std::max(sa, sb));
      if (!(hi > lo)) continue;
      const int steps = std::max(1, static_cast<int>(std::ceil((hi - lo) / kMarkStepM)));
      const Vec2 a = l.a + lo * u, b = l.a + hi * u;
      for (int m = 0; m <= steps; ++m) {
        const Vec2 x = a + (static_cast<double>(m) / steps) * (b - a);
        cells_.insert({Cell(x.x()), Cell(x.y())});
      }
    }
  }

  // Whether some point of s lies strictly inside the triangle (o, p, q):
  // s clipped to the triangle's three open half-planes is not empty.
  static bool Inside(const Segment2& s, const Vec2& o, const Vec2& p, const Vec2& q) {
    const double orient = geometry::Cross(p - o, q - o);
    if (orient == 0.0) return false;
    const Vec2 corners[3] = {o, p, q};
    double lo = 0.0, hi = 1.0;
    for (int e = 0; e < 3; ++e) {
      const Vec2& x = corners[e];
      const Vec2& y = corners[(e + 1) % 3];
      // f(t) = orient-signed cross of the edge with s(t) - x, > 0 inside.
      const double f0 = (orient > 0 ? 1.0 : -1.0) * geometry::Cross(y - x, s.a - x);
      const double f1 = (orient > 0 ? 1.0 : -1.0) * geometry::Cross(y - x, s.b - x);
      if (f0 <= 0.0 && f1 <= 0.0) return false;
      if (f0 > 0.0 && f1 > 0.0) continue;
      const double t = f0 / (f0 - f1);  // where f crosses zero
      if (f0 > 0.0)
        hi = std::min(hi, t);
      else
        lo = std::max(lo, t);
    }
    return lo < hi;
  }

  // Where the ray from o through x meets the line la + t u, going forward.
  static bool Shadow(const Vec2& o, const Vec2& x, const Vec2& la, const Vec2& u, double* t) {
    Eigen::Matrix2d m;
    m.col(0) = x - o;
    m.col(1) = -u;
    if (std::abs(m.determinant()) < 1e-12) return false;
    const Eigen::Vector2d st = m.colPivHouseholderQr().solve(la - o);
    if (!(st(0) > 0.0)) return false;
    *t = st(1);
    return true;
  }

  std::set<std::pair<int64_t, int64_t>> cells_;
};

// A piece is pierced when a sample of its fitted segment, 0.5 m at each end
// aside, lies in a seen-free cell: it then lies on one wall with no other piece.
bool PiercedRef(const Segment2& s, const SeenFree& seen) {
  const double length = s.length();
  if (!(length > 1.0)) return false;
  return seen.AnyFree(s.a, s.direction() / length, 0.5, length - 0.5);
}

enum class GapJoin { kNone, kJoined, kVetoed, kUnproven };

// Rule (a) extended by the evidence: L the longer piece (ties: the smaller
// id), S the other; the included angle <= delta, both ends of S within
// wall_offset_m of L's line, a gap along L beyond wall_gap_m but at most
// wall_occluded_gap_m and wall_occluded_gap_ratio times S's length: they lie
// on one wall unless a sample of the gap on L's line is seen free.
GapJoin OccludedGap(const Segment2& p, ClusterId p_id, const Segment2& q, ClusterId q_id,
                    const FusionParams& params, const SeenFree& seen,
                    const ProvenOccluded& proven) {
  const bool p_longer = p.length() > q.length() || (p.length() == q.length() && p_id < q_id);
  const Segment2& l = p_longer ? p : q;
  const Segment2& s = p_longer ? q : p;
  const Vec2 u = l.direction().normalized();
  const Vec2 v = s.direction().normalized();
  if (std::abs(geometry::Cross(u, v)) > std::sin(params.delta_rad)) return GapJoin::kNone;
  if (std::abs(geometry::Cross(u, s.a - l.a)) > params.wall_offset_m ||
      std::abs(geometry::Cross(u, s.b - l.a)) > params.wall_offset_m) {
    return GapJoin::kNone;
  }
  const double ta = u.dot(s.a - l.a), tb = u.dot(s.b - l.a);
  const double before = -std::max(ta, tb);             // S ends before L starts
  const double after = std::min(ta, tb) - l.length();  // S starts after L ends
  const double gap = std::max(before, after);
  if (!(gap > params.wall_gap_m) || gap > params.wall_occluded_gap_m ||
      gap > params.wall_occluded_gap_ratio * s.length()) {
    return GapJoin::kNone;
  }
  const bool seen_through = before > after ? seen.AnyFree(l.a, u, -before, 0.0)
                                           : seen.AnyFree(l.a, u, l.length(), l.length() + after);
  if (seen_through) return GapJoin::kVetoed;
  if (gap <= params.wall_proof_gap_m) {
    // Up to wall_proof_gap_m, only where proven occluded, a cell at each end aside.
    const double t0 = before > after ? -before : l.length();
    const double t1 = before > after ? 0.0 : l.length() + after;
    const double trim = ProvenOccluded::kCellM;
    const bool all = t1 - t0 > 2.0 * trim ? proven.AllProven(l.a, u, t0 + trim, t1 - trim)
                                          : proven.Proven(l.a + 0.5 * (t0 + t1) * u);
    if (!all) return GapJoin::kUnproven;
  }
  return GapJoin::kJoined;
}

}  // namespace

BatchResult BatchFuse(const std::vector<BatchObservation>& observations,
                      const FusionParams& params) {
  std::vector<Flat> all;
  for (const BatchObservation& o : observations) {
    for (const GroundFeature& f : o.features) all.push_back({f, o.id});
  }
  std::vector<Unit> features;
  for (const Flat& f : all) {
    features.push_back({f.feature.id,
                        f.feature.segment.midpoint(),
                        {f.feature.segment.a, f.feature.segment.b},
                        {f.observation}});
  }
  const std::vector<std::vector<size_t>> components =
      Components(all.size(), [&](size_t i, size_t j) {
        return i != j && all[i].observation != all[j].observation &&
               MeetsAllCriteria(all[i].feature.segment, all[j].feature.segment, params);
      });

  // The guard's groups of every component: the clusters.
  BatchResult result;
  std::vector<std::vector<size_t>> members_of;  // per cluster, indices into `all`
  for (const std::vector<size_t>& component : components) {
    std::vector<std::vector<size_t>> groups;
    GuardGroups(
        features, component, params,
        [&](const std::vector<size_t>& head, const std::vector<size_t>& tail) {
          return Publishable(features, head, params) && Publishable(features, tail, params);
        },
        &groups);
    for (std::vector<size_t>& group : groups) {
      std::sort(group.begin(), group.end());
      members_of.push_back(group);
    }
  }
  const auto make = [&](const std::vector<size_t>& members) {
    BatchCluster c;
    std::vector<Vec2> endpoints;
    std::set<ObservationId> support;
    for (size_t i : members) {
      c.members.push_back(all[i].feature.id);
      endpoints.push_back(all[i].feature.segment.a);
      endpoints.push_back(all[i].feature.segment.b);
      support.insert(all[i].observation);
    }
    std::sort(c.members.begin(), c.members.end());
    c.id = c.members.front();
    c.support = static_cast<uint32_t>(support.size());
    c.published = c.support >= params.min_support;
    Fit fit;
    c.fitted = FittedSegment(endpoints, &fit);
    c.segment = c.fitted;
    return c;
  };
  std::vector<size_t> published;  // indices into result.clusters
  for (const std::vector<size_t>& members : members_of) {
    result.clusters.push_back(make(members));
    if (result.clusters.back().published) published.push_back(result.clusters.size() - 1);
  }

  // Consolidation (fusion/wall_consolidation.h): components of OnOneWall
  // over the published clusters, through the guard with clusters as units.
  // With free-space evidence: pierced pieces join nothing, and pieces also
  // join across an occluded gap that nothing was seen through.
  bool any_sensor = false;
  for (const BatchObservation& o : observations) any_sensor |= o.has_sensor && !o.features.empty();
  result.evidence.on = params.consolidate && params.wall_occluded_gap_m > 0.0 && any_sensor;
  const SeenFree seen(result.evidence.on ? observations : std::vector<BatchObservation>(),
                      params.wall_free_min_count);
  const ProvenOccluded proven(result.evidence.on && params.wall_proof_gap_m > 0.0
                                  ? observations
                                  : std::vector<BatchObservation>(),
                              params);
  std::vector<bool> pierced(published.size(), false);
  std::vector<std::vector<GapJoin>> gap_join(published.size(),
                                             std::vector<GapJoin>(published.size()));
  if (result.evidence.on) {
    result.evidence.free_cells = seen.free_cells();
    for (size_t i = 0; i < published.size(); ++i) {
      pierced[i] = PiercedRef(result.clusters[published[i]].fitted, seen);
      result.evidence.pierced += pierced[i];
    }
    for (size_t i = 0; i < published.size(); ++i) {
      for (size_t j = i + 1; j < published.size(); ++j) {
        const BatchCluster& p = result.clusters[published[i]];
        const BatchCluster& q = result.clusters[published[j]];
        gap_join[i][j] = gap_join[j][i] =
            OccludedGap(p.fitted, p.id, q.fitted, q.id, params, seen, proven);
        if (pierced[i] || pierced[j]) continue;
        result.evidence.occluded_joins += gap_join[i][j] == GapJoin::kJoined;
        result.evidence.seen_free_vetoes += gap_join[i][j] == GapJoin::kVetoed;
      }
    }
  }
  const std::vector<std::vector<size_t>> walls_of =
      Components(published.size(), [&](size_t i, size_t j) {
        const BatchCluster& p = result.clusters[published[i]];
        const BatchCluster& q = result.clusters[published[j]];
        if (i == j || !params.consolidate || pierced[i] || pierced[j]) return false;
        return OnOneWall(p.fitted, p.id, q.fitted, q.id, params) ||
               gap_join[i][j] == GapJoin::kJoined;
      });
  std::vector<Fit> fits;
  for (const std::vector<size_t>& component : walls_of) {
    std::vector<Unit> units;
    std::vector<size_t> index(component.size());
    for (size_t k = 0; k < component.size(); ++k) {
      const size_t c = published[component[k]];
      Unit u{result.clusters[c].id, result.clusters[c].fitted.midpoint(), {}, {}};
      for (size_t i : members_of[c]) {
        u.points.push_back(all[i].feature.segment.a);
        u.points.push_back(all[i].feature.segment.b);
      }
      units.push_back(std::move(u));
      index[k] = k;
    }
    // Consolidation's guard may not cut between near-identical pieces
    // (fusion/wall_consolidation.h, rule b: endpoints within wall_offset_m).
    const auto twins = [&](const std::vector<size_t>& head, const std::vector<size_t>& tail) {
      for (size_t i : head) {
        for (size_t j : tail) {
          if (NearIdentical(result.clusters[published[component[i]]].fitted,
                            result.clusters[published[component[j]]].fitted,
                            params.wall_offset_m)) {
            return true;
          }
        }
      }
      return false;
    };
    std::vector<std::vector<size_t>> groups;
    if (component.size() > 1) {
      GuardGroups(
          units, index, params,
          [&](const std::vector<size_t>& head, const std::vector<size_t>& tail) {
            return !twins(head, tail);
          },
          &groups);
    } else {
      groups.push_back(index);
    }
    for (const std::vector<size_t>& group : groups) {
      std::vector<size_t> members;
      for (size_t k : group) {
        const std::vector<size_t>& m = members_of[published[component[k]]];
        members.insert(members.end(), m.begin(), m.end());
      }
      result.walls.push_back(make(members));
      std::vector<Vec2> endpoints;
      for (size_t i : members) {
        endpoints.push_back(all[i].feature.segment.a);
        endpoints.push_back(all[i].feature.segment.b);
      }
      Fit fit;
      FittedSegment(endpoints, &fit);
      fits.push_back(fit);
    }
  }

  // Corner rule: mutual nearest endpoints of different walls, or greedy in
  // (wall id, end) order (fusion/corner_snap.h).
  struct End {
    size_t wall;
    int end;
    Vec2 p;
  };
  std::vector<size_t> wall_order(result.walls.size());
  for (size_t k = 0; k < wall_order.size(); ++k) wall_order[k] = k;
  std::sort(wall_order.begin(), wall_order.end(),
            [&](size_t x, size_t y) { return result.walls[x].id < result.walls[y].id; });
  std::vector<End> ends;  // in (wall id, end) order
  for (size_t k : wall_order) {
    ends.push_back({k, 0, result.walls[k].fitted.a});
    ends.push_back({k, 1, result.walls[k].fitted.b});
  }
  // The nearest endpoint of another wall closer than snap_m, not excluded;
  // ties to the first in (id, end) order.
  const auto nearest = [&](size_t e, const std::vector<bool>& excluded) {
    long best = -1;
    for (size_t o = 0; o < ends.size(); ++o) {
      if (ends[o].wall == ends[e].wall || excluded[o]) continue;
      const double d = (ends[o].p - ends[e].p).norm();
      if (!(d < params.snap_m)) continue;
      if (best < 0 || d < (ends[best].p - ends[e].p).norm()) best = static_cast<long>(o);
    }
    return best;
  };
  // partner[e]: the endpoint e pairs with, -1 if none.
  std::vector<long> partner(ends.size(), -1);
  const std::vector<bool> none(ends.size(), false);
  std::vector<bool> paired(ends.size(), false);
  for (size_t e = 0; e < ends.size(); ++e) {
    if (params.corner_pairing == CornerPairing::kMutualNearest) {
      const long o = nearest(e, none);
      if (o >= 0 && nearest(static_cast<size_t>(o), none) == static_cast<long>(e)) partner[e] = o;
    } else if (!paired[e]) {
      const long o = nearest(e, paired);
      if (o < 0) continue;
      partner[e] = o;
      partner[static_cast<size_t>(o)] = static_cast<long>(e);
      paired[e] = paired[static_cast<size_t>(o)] = true;
    }
  }
  std::vector<Vec2> moved(ends.size());
  for (size_t e = 0; e < ends.size(); ++e) {
    moved[e] = ends[e].p;
    const long o = partner[e];
    if (o < 0) continue;
    // Both ends of this wall paired with ends of the same wall: no corner.
    const long so = partner[e ^ 1];  // ends are pushed in pairs: 2k (a), 2k+1 (b)
    if (so >= 0 && ends[static_cast<size_t>(so)].wall == ends[static_cast<size_t>(o)].wall)
      continue;
    const End& other = ends[static_cast<size_t>(o)];
    moved[e] = Joint(ends[e].p, fits[ends[e].wall], other.p, fits[other.wall], params);
  }
  for (size_t e = 0; e < ends.size(); ++e) {
    Segment2& s = result.walls[ends[e].wall].segment;
    (ends[e].end == 0 ? s.a : s.b) = moved[e];
  }
  const auto by_id = [](const BatchCluster& x, const BatchCluster& y) { return x.id < y.id; };
  std::sort(result.clusters.begin(), result.clusters.end(), by_id);
  std::sort(result.walls.begin(), result.walls.end(), by_id);
  return result;
}

}  // namespace mapd::fusion::testing
