#include "fusion/engine.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <string>
#include <unordered_map>
#include <unordered_set>
#include <utility>

#include "fusion/chain_guard.h"
#include "fusion/cluster_stats.h"
#include "fusion/corner_snap.h"
#include "fusion/criteria.h"
#include "fusion/engine_impl.h"
#include "fusion/engine_inspector.h"
#include "fusion/grid_index.h"
#include "fusion/support_counter.h"
#include "geometry/convex_hull2.h"

namespace mapd::fusion {

using geometry::Segment2;
using geometry::Vec2;

namespace {

// Input bounds (engine.h): coordinates beyond this are refused as absurd.
constexpr double kMaxAbsCoordinateM = 1e6;
// Shorter segments are refused as zero-length: they have no direction.
constexpr double kMinSegmentLengthM = 1e-9;
// Added to exact search radii so that rounding never hides a candidate.
constexpr double kSearchSlackM = 1e-6;

// The larger of the two squared endpoint distances between f and g, in the
// pairing (a-a, b-b or a-b, b-a) that makes it smaller, m^2.
double EndpointDistanceSq(const Segment2& f, const Segment2& g) {
  const double same = std::max((f.a - g.a).squaredNorm(), (f.b - g.b).squaredNorm());
  const double swapped = std::max((f.a - g.b).squaredNorm(), (f.b - g.a).squaredNorm());
  return std::min(same, swapped);
}

Status CheckPoint(const Vec2& p, size_t index, const char* name) {
  if (!p.allFinite()) {
    return Status::InvalidArgument("features[" + std::to_string(index) + "].segment." + name +
                                   " is not finite");
  }
  if (p.cwiseAbs().maxCoeff() > kMaxAbsCoordinateM) {
    return Status::InvalidArgument("features[" + std::to_string(index) + "].segment." + name +
                                   " is beyond 1e6 m");
  }
  return Status::Ok();
}

}  // namespace

std::vector<std::vector<uint32_t>> FusionEngine::Impl::GroupNodes(uint32_t root) const {
  std::vector<uint32_t> nodes;
  nodes.reserve(size_[root]);
  uint32_t node = root;
  do {
    nodes.push_back(node);
    node = next_member_[node];
  } while (node != root);
  std::vector<GuardMember> members;
  members.reserve(nodes.size());
  for (uint32_t n : nodes) {
    members.push_back({anchors_[n].id, anchors_[n].segment,
                       bounded_ && folded_[n] ? &folded_[n]->moments : nullptr});
  }
  // A cut never leaves a piece below min_support (chain_guard.h, step 4).
  const auto publishable = [&](const std::vector<uint32_t>& subset) {
    return ReachesMinSupport(nodes, subset);
  };
  std::vector<std::vector<uint32_t>> groups =
      SplitChain(members, params_.chain_max_rms_m, params_.chain_max_sse_ratio,
                 [&](const std::vector<uint32_t>& head, const std::vector<uint32_t>& tail) {
                   return publishable(head) && publishable(tail);
                 });
  for (std::vector<uint32_t>& group : groups) {
    for (uint32_t& index : group) index = nodes[index];
  }
  return groups;
}

ClusterStats FusionEngine::Impl::StatsOf(const std::vector<uint32_t>& nodes) const {
  if (bounded_) {
    ClusterStats s = NodeStats(nodes.front());
    for (size_t i = 1; i < nodes.size(); ++i) s.Merge(NodeStats(nodes[i]), support_cap_);
    return s;
  }
  ClusterStats s = ClusterStats::OfFeature(anchors_[nodes.front()], observation_of_[nodes.front()],
                                           robot_of_[nodes.front()]);
  std::vector<Vec2> points = s.hull;
  for (size_t i = 1; i < nodes.size(); ++i) {
    const GroundFeature& f = anchors_[nodes[i]];
    s.id = std::min(s.id, f.id);
    ++s.member_count;
    s.plane_members += f.origin == FeatureOrigin::kPlane ? 1 : 0;
    s.moments.Add(f.segment.a);
    s.moments.Add(f.segment.b);
    points.push_back(f.segment.a);
    points.push_back(f.segment.b);
    s.z_min_m = std::min(s.z_min_m, f.z_min_m);
    s.z_max_m = std::max(s.z_max_m, f.z_max_m);
    s.observations.Add(observation_of_[nodes[i]], support_cap_);
    s.robots.push_back(robot_of_[nodes[i]]);
  }
  s.hull = geometry::ConvexHull(std::move(points));
  std::sort(s.robots.begin(), s.robots.end());
  s.robots.erase(std::unique(s.robots.begin(), s.robots.end()), s.robots.end());
  return s;
}

bool FusionEngine::Impl::ReachesMinSupport(const std::vector<uint32_t>& nodes,
                                           const std::vector<uint32_t>& subset) const {
  // StatsOf(subset).support() >= min_support without the hulls and moments:
  // the chain guard asks this of every candidate cut, and on a long component
  // the hulls made regrouping cost O(n^2 log n) (issue 46's profile: 45 % of
  // the fuser in ConvexHull). Merging the same counters in the same order
  // gives StatsOf's count, and counts never fall as counters merge
  // (support_counter.h), so stopping at min_support gives the same answer.
  SupportCounter support;
  for (uint32_t i : subset) {
    const uint32_t n = nodes[i];
    if (bounded_ && folded_[n]) {
      support.Merge(folded_[n]->observations, support_cap_);
    } else {
      support.Add(observation_of_[n], support_cap_);
    }
    if (support.count() >= params_.min_support) return true;
  }
  return false;
}

void FusionEngine::Impl::FileInGrid(uint32_t node, const Segment2& segment) {
  const FeatureCircle c = CircleOf(segment);
  grid_.Insert(c.centre, {segment, c.centre, c.radius_m, node});
  if (bounded_) cover_grid_.Insert(c.centre, {segment, node});
}

uint32_t FusionEngine::Impl::Find(uint32_t x) {
  uint32_t root = x;
  while (parent_[root] != root) root = parent_[root];
  while (parent_[x] != root) {  // path compression
    const uint32_t next = parent_[x];
    parent_[x] = root;
    x = next;
  }
  return root;
}

uint32_t FusionEngine::Impl::FindConst(uint32_t x) const {
  while (parent_[x] != x) x = parent_[x];
  return x;
}

uint32_t FusionEngine::Impl::Union(uint32_t a, uint32_t b, std::vector<ClusterId>* merged_ids) {
  if (size_[a] < size_[b]) std::swap(a, b);  // union by size: a survives
  merged_ids->push_back(stats_[a]->id);
  merged_ids->push_back(stats_[b]->id);
  parent_[b] = a;
  size_[a] += size_[b];
  if (guard_on_) std::swap(next_member_[a], next_member_[b]);  // splice the member lists
  stats_[a]->Merge(std::move(*stats_[b]), support_cap_);
  stats_[b].reset();
  if (bounded_) {
    bounds_[a].min = bounds_[a].min.cwiseMin(bounds_[b].min);
    bounds_[a].max = bounds_[a].max.cwiseMax(bounds_[b].max);
  }
  --cluster_count_;
  return a;
}

Status FusionEngine::Impl::Validate(ObservationId observation,
                                    const std::vector<GroundFeature>& features) const {
  // Bounded mode remembers no observation ids but the last one: the caller
  // guarantees the rest (engine.h).
  if (bounded_ ? (has_last_observation_ && observation == last_observation_)
               : observations_.count(observation) != 0) {
    return Status::InvalidArgument("observation " + std::to_string(observation) +
                                   " was added before");
  }
  // Duplicate ids in the batch: a scan of the earlier ones for a batch of a
  // scan's size (no allocation per feature), a set beyond.
  constexpr size_t kScanBelow = 64;
  std::unordered_set<FeatureId> batch_ids;
  const auto seen_in_batch = [&](size_t i) {
    if (features.size() < kScanBelow) {
      for (size_t j = 0; j < i; ++j) {
        if (features[j].id == features[i].id) return true;
      }
      return false;
    }
    return !batch_ids.insert(features[i].id).second;
  };
  for (size_t i = 0; i < features.size(); ++i) {
    const GroundFeature& f = features[i];
    const std::string name = "features[" + std::to_string(i) + "]";
    MAPD_RETURN_IF_ERROR(CheckPoint(f.segment.a, i, "a"));
    MAPD_RETURN_IF_ERROR(CheckPoint(f.segment.b, i, "b"));
    if (!(f.segment.length() >= kMinSegmentLengthM)) {
      return Status::InvalidArgument(name + " has zero length");
    }
    if (f.segment.length() > params_.max_wall_length_m) {
      return Status::InvalidArgument(name + " is longer than max_wall_length_m (" +
                                     std::to_string(params_.max_wall_length_m) + " m)");
    }
    if (!std::isfinite(f.z_min_m) || !std::isfinite(f.z_max_m) ||
        std::abs(f.z_min_m) > kMaxAbsCoordinateM || std::abs(f.z_max_m) > kMaxAbsCoordinateM ||
        f.z_min_m > f.z_max_m) {
      return Status::InvalidArgument(name + " has an invalid z range");
    }
    if ((!bounded_ && node_of_.count(f.id) != 0) || seen_in_batch(i)) {
      return Status::InvalidArgument(name + ": feature id " + std::to_string(f.id) +
                                     " is not unique");
    }
  }
  return Status::Ok();
}

void FusionEngine::Impl::LinkToEarlier(uint32_t node, const GroundFeature& f,
                                       std::vector<ClusterId>* merged_ids) {
  const FeatureCircle circle = CircleOf(f.segment);
  // Criterion 3 (eq. 12) needs dist(O_g, segment f) <= eta: only centres in
  // the band of half width eta around f can link. It also bounds the centre
  // distance: dist(O_g, segment f) >= D - R_f, so d_max <= eta implies
  // D <= min(R_f, R_g) + eta. Both hold for every gamma (gamma = 0 included),
  // so this search finds every candidate.
  const double band_m = params_.eta_m + kSearchSlackM;
  uint32_t root = Find(node);
  const size_t max_candidates = bounded_ ? params_.max_link_candidates : SIZE_MAX;
  grid_.ForEachNearSegment(
      f.segment, band_m,
      [&](const IndexedFeature& g) {
        const double bound_m =
            std::min(circle.radius_m, g.radius_m) + params_.eta_m + kSearchSlackM;
        if ((g.centre - circle.centre).squaredNorm() > bound_m * bound_m) return;
        const uint32_t other_root = Find(g.node);
        if (other_root == root) return;  // an edge inside a component changes nothing
        if (geometry::PointSegmentDistance(g.centre, f.segment) > band_m) return;
        if (!MeetsAllCriteria(f.segment, g.segment, params_)) return;
        if (bounded_ && !MayLink(root, other_root)) return;
        root = Union(root, other_root, merged_ids);
      },
      max_candidates);
}

bool FusionEngine::Impl::MayLink(uint32_t a, uint32_t b) const {
  // The extent cap (params.h), on the components' bounding boxes (bounds_:
  // the hulls' own would cost a pass over their vertices per candidate, 35 %
  // of the city's fusion time).
  const Vec2 lo = bounds_[a].min.cwiseMin(bounds_[b].min);
  const Vec2 hi = bounds_[a].max.cwiseMax(bounds_[b].max);
  if ((hi - lo).norm() > params_.max_wall_length_m) return false;
  if (size_[a] + size_[b] <= params_.max_component_nodes) return true;
  // Past the cap only a component the guard will not regroup may grow.
  geometry::PointMoments2 both = stats_[a]->moments;
  both.Merge(stats_[b]->moments);
  return !guard_on_ || !ChainMayNeedSplit(both, params_.chain_max_rms_m);
}

uint32_t FusionEngine::Impl::NewNode(const GroundFeature& f, ObservationId observation,
                                     RobotId robot) {
  const uint32_t node = static_cast<uint32_t>(parent_.size());
  parent_.push_back(node);
  size_.push_back(1);
  stats_.push_back(std::make_unique<ClusterStats>(ClusterStats::OfFeature(f, observation, robot)));
  if (bounded_) {
    bounds_.push_back({f.segment.a.cwiseMin(f.segment.b), f.segment.a.cwiseMax(f.segment.b)});
  }
  node_of_.emplace(f.id, node);
  if (keeps_anchors()) anchors_.push_back(f);
  if (guard_on_) {
    observation_of_.push_back(observation);
    robot_of_.push_back(robot);
    if (bounded_) folded_.push_back(nullptr);
    next_member_.push_back(node);
  }
  ++cluster_count_;
  return node;
}

bool FusionEngine::Impl::FindCover(const GroundFeature& f, uint32_t* node) const {
  // Both endpoints within cover_m puts the centres within cover_m too.
  const Vec2 centre = f.segment.midpoint();
  const double cover_sq = params_.cover_m * params_.cover_m;
  double best_sq = cover_sq;
  bool found = false;
  cover_grid_.ForEachNear(
      centre, params_.cover_m + kSearchSlackM,
      [&](const CoverItem& g) {
        if ((g.segment.midpoint() - centre).squaredNorm() > cover_sq) return;
        const Segment2& segment = g.segment;
        const double d_sq = EndpointDistanceSq(f.segment, segment);
        if (d_sq > best_sq || (found && d_sq == best_sq && g.node > *node)) return;
        if (stats_[FindConst(g.node)]->support() < support_cap_) return;  // not established
        if (!MeetsAllCriteria(f.segment, segment, params_)) return;
        best_sq = d_sq;
        *node = g.node;
        found = true;
      },
      params_.max_link_candidates);
  return found;
}

void FusionEngine::Impl::Add(ObservationId observation, RobotId robot, const Vec2* sensor_xy_m,
                             const std::vector<GroundFeature>& features, ChangeFeed* changes) {
  if (sensor_xy_m != nullptr) {
    // Evidence first: the walls resolved below see this observation's views.
    std::vector<Segment2> segments;
    segments.reserve(features.size());
    for (const GroundFeature& f : features) segments.push_back(f.segment);
    consolidator_.AddObservation(*sensor_xy_m, segments);
  }
  if (!bounded_) observations_.insert(observation);
  last_observation_ = observation;
  has_last_observation_ = true;
  raw_feature_count_ += features.size();
  // Features of one observation are never linked directly (the paper compares
  // time k with k - i only), so new nodes are filed only after all queries.
  std::vector<ClusterId> merged_ids;
  std::vector<uint32_t> nodes(features.size());
  std::vector<bool> folded(features.size(), false);
  for (size_t i = 0; i < features.size(); ++i) {
    const GroundFeature& f = features[i];
    if (bounded_ && FindCover(f, &nodes[i])) {
      // Folded: the cluster's statistics grow, its node set does not. Its id
      // may change (a smaller member id), so Publish treats it as touched.
      ClusterStats& cluster = *stats_[Find(nodes[i])];
      merged_ids.push_back(cluster.id);
      // A point strictly inside the representative's hull is strictly inside
      // the cluster's, which contains it: one small test spares the large one.
      bool inside_rep_hull = false;
      if (guard_on_) {
        std::unique_ptr<ClusterStats>& rep = folded_[nodes[i]];
        if (!rep) rep = std::make_unique<ClusterStats>(NodeStats(nodes[i]));
        inside_rep_hull = geometry::StrictlyInsideHull(rep->hull, f.segment.a) &&
                          geometry::StrictlyInsideHull(rep->hull, f.segment.b);
        rep->AddFeature(f, observation, robot, support_cap_, inside_rep_hull);
      }
      cluster.AddFeature(f, observation, robot, support_cap_, inside_rep_hull);
      geometry::Box2& box = bounds_[Find(nodes[i])];
      box.min = box.min.cwiseMin(f.segment.a.cwiseMin(f.segment.b));
      box.max = box.max.cwiseMax(f.segment.a.cwiseMax(f.segment.b));
      folded[i] = true;
      continue;
    }
    nodes[i] = NewNode(f, observation, robot);
  }
  // A folded feature stands in for its representative both ways: later
  // features are tested against the representative, and it links through the
  // representative's links (made when the representative was added). So only
  // new representatives search for links: on a revisited site that is rare,
  // and the work per observation falls as the map fills in.
  for (size_t i = 0; i < features.size(); ++i) {
    if (!folded[i]) LinkToEarlier(nodes[i], features[i], &merged_ids);
  }
  for (size_t i = 0; i < features.size(); ++i) {
    if (!folded[i]) FileInGrid(nodes[i], features[i].segment);
  }
  std::vector<uint32_t> roots;
  roots.reserve(nodes.size());
  for (uint32_t node : nodes) roots.push_back(Find(node));
  std::sort(roots.begin(), roots.end());
  roots.erase(std::unique(roots.begin(), roots.end()), roots.end());
  // Components that gained a node (and any link: only new nodes link) are
  // refitted in full; the others only grew by folds, which may settle.
  std::vector<uint32_t> grown;
  for (size_t i = 0; i < features.size(); ++i) {
    if (!folded[i]) grown.push_back(Find(nodes[i]));
  }
  std::sort(grown.begin(), grown.end());
  ChangeFeed feed;
  Publish(roots, grown, merged_ids, &feed);
  if (changes != nullptr) *changes = std::move(feed);
}

void FusionEngine::Impl::Publish(const std::vector<uint32_t>& roots,
                                 const std::vector<uint32_t>& grown,
                                 const std::vector<ClusterId>& merged_ids, ChangeFeed* feed) {
  // Fitted endpoints that appeared, moved or vanished: the corner result can
  // change near them (CornerSnapper::CollectAffected).
  std::vector<Vec2> moved_points;
  // The groups published before by the components this Add touched: every such
  // component was merged into a root of `roots`, so its id is in merged_ids.
  std::vector<ClusterId> old_groups;
  old_groups.reserve(merged_ids.size());
  // Components the guard had cut: a piece of one holds a group's statistics,
  // not the component's, so it may not settle into the whole.
  std::vector<ClusterId> were_cut;
  for (ClusterId id : merged_ids) {
    if (auto split = split_.find(id); split != split_.end()) {
      old_groups.insert(old_groups.end(), split->second.published.begin(),
                        split->second.published.end());
      extra_groups_ -= split->second.group_count - 1;
      split_.erase(split);
      were_cut.push_back(id);
    } else if (consolidator_.HasPiece(id)) {
      old_groups.push_back(id);
    }
  }
  // The touched components' groups now: refit once each, publish at min_support.
  std::vector<ClusterId> new_groups;
  new_groups.reserve(roots.size());
  std::vector<ClusterId> settled;  // pieces whose walls only need new counts
  for (uint32_t root : roots) {
    const ClusterStats& whole = *stats_[root];
    std::vector<std::vector<uint32_t>> groups;
    if (MayCut(root)) groups = GroupNodes(root);
    if (groups.size() <= 1) {  // one group: the component itself
      if (whole.support() < params_.min_support) continue;
      if (std::binary_search(grown.begin(), grown.end(), root) ||
          std::find(were_cut.begin(), were_cut.end(), whole.id) != were_cut.end()) {
        PublishGroup(whole);
      } else {
        PublishFolded(whole, &settled);
      }
      new_groups.push_back(whole.id);
      continue;
    }
    SplitRecord& record = split_[whole.id];
    record.group_count = static_cast<uint32_t>(groups.size());
    extra_groups_ += groups.size() - 1;
    for (const std::vector<uint32_t>& group : groups) {
      const ClusterStats stats = StatsOf(group);
      if (stats.support() < params_.min_support) continue;
      PublishGroup(stats);
      new_groups.push_back(stats.id);
      record.published.push_back(stats.id);
    }
  }
  // Groups published before and gone now leave the consolidator.
  std::sort(new_groups.begin(), new_groups.end());
  std::sort(old_groups.begin(), old_groups.end());
  old_groups.erase(std::unique(old_groups.begin(), old_groups.end()), old_groups.end());
  for (ClusterId id : old_groups) {
    if (!std::binary_search(new_groups.begin(), new_groups.end(), id)) consolidator_.Erase(id);
  }
  // The walls those changes touched: publish them, drop the ones gone.
  std::vector<ClusterId> removed_walls;
  std::vector<WallConsolidator::Wall> walls;
  consolidator_.Resolve(&removed_walls, &walls);
  for (ClusterId id : removed_walls) {
    auto it = published_.find(id);
    if (it == published_.end()) continue;
    moved_points.push_back(it->second.fitted.a);
    moved_points.push_back(it->second.fitted.b);
    snapper_.Erase(id);
    published_.erase(it);
    feed->removed.push_back(id);
  }
  // Walls whose counts alone changed: not corner candidates, nothing of theirs moved.
  std::vector<ClusterId> recounted;
  for (const WallConsolidator::Wall& wall : walls) {
    PublishWall(wall, feed, &moved_points, &recounted);
  }
  // The walls of settled pieces that Resolve did not recompute: same
  // geometry, new counts.
  for (ClusterId piece : settled) {
    if (!consolidator_.OnAWall(piece)) continue;
    const ClusterId id = consolidator_.WallOf(piece);
    if (std::any_of(walls.begin(), walls.end(),
                    [id](const WallConsolidator::Wall& w) { return w.stats().id == id; })) {
      continue;  // recomputed whole: PublishWall set its counts
    }
    auto published = published_.find(id);
    if (published == published_.end()) continue;  // not expected: every wall is published
    if (CurrentCounts(consolidator_.WallPieces(id)).Set(&published->second)) {
      recounted.push_back(id);
    }
  }
  // The corner pass, local to the moved endpoints.
  std::vector<ClusterId> dirty = feed->added;
  dirty.insert(dirty.end(), feed->updated.begin(), feed->updated.end());
  snapper_.CollectAffected(moved_points, kSearchSlackM, &dirty);
  std::sort(dirty.begin(), dirty.end());
  dirty.erase(std::unique(dirty.begin(), dirty.end()), dirty.end());
  std::vector<ClusterId> changed(feed->added);
  changed.insert(changed.end(), feed->updated.begin(), feed->updated.end());
  std::sort(changed.begin(), changed.end());
  const std::vector<Segment2> snapped_all = snapper_.SnappedAll(dirty);
  for (size_t k = 0; k < dirty.size(); ++k) {
    const ClusterId id = dirty[k];
    FusedFeature& fused = published_.at(id);
    const Segment2& snapped = snapped_all[k];
    const bool moved = snapped.a != fused.segment.a || snapped.b != fused.segment.b;
    fused.segment = snapped;
    if (moved && !std::binary_search(changed.begin(), changed.end(), id)) {
      feed->updated.push_back(id);  // a neighbour's corner moved it
    }
  }
  feed->updated.insert(feed->updated.end(), recounted.begin(), recounted.end());
  std::sort(feed->added.begin(), feed->added.end());
  std::sort(feed->updated.begin(), feed->updated.end());
  feed->updated.erase(std::unique(feed->updated.begin(), feed->updated.end()), feed->updated.end());
  std::sort(feed->removed.begin(), feed->removed.end());
}

void FusionEngine::Impl::PublishFolded(const ClusterStats& whole, std::vector<ClusterId>* settled) {
  const ClusterStats::Fit fit = whole.Refit();
  // Only a cluster that is a node's own feature id: CurrentStats finds it.
  if (bounded_ && params_.refit_tolerance_m > 0.0 && node_of_.count(whole.id) != 0 &&
      consolidator_.Settle(whole, fit, params_.refit_tolerance_m)) {
    settled->push_back(whole.id);
    return;
  }
  consolidator_.Upsert(whole, fit);
}

const ClusterStats& FusionEngine::Impl::CurrentStats(ClusterId piece) const {
  if (auto node = node_of_.find(piece); node != node_of_.end() && split_.count(piece) == 0) {
    const ClusterStats& whole = *stats_[FindConst(node->second)];
    if (whole.id == piece) return whole;
  }
  return consolidator_.pieces().at(piece);
}

WallCounts FusionEngine::Impl::CurrentCounts(const std::vector<ClusterId>& pieces) const {
  const ClusterStats& first = CurrentStats(pieces.front());
  WallCounts counts{first.member_count, first.plane_members, first.support(), first.z_min_m,
                    first.z_max_m};
  if (pieces.size() == 1) return counts;
  SupportCounter support = first.observations;
  for (size_t i = 1; i < pieces.size(); ++i) {
    const ClusterStats& part = CurrentStats(pieces[i]);
    counts.member_count += part.member_count;
    counts.plane_members += part.plane_members;
    counts.z_min_m = std::min(counts.z_min_m, part.z_min_m);
    counts.z_max_m = std::max(counts.z_max_m, part.z_max_m);
    support.Merge(part.observations, support_cap_);
  }
  counts.support = support.count();
  return counts;
}

bool WallCounts::Set(FusedFeature* f) const {
  const bool changed = f->member_count != member_count || f->plane_members != plane_members ||
                       f->support != support || f->z_min_m != z_min_m || f->z_max_m != z_max_m;
  f->member_count = member_count;
  f->plane_members = plane_members;
  f->support = support;
  f->z_min_m = z_min_m;
  f->z_max_m = z_max_m;
  return changed;
}

void FusionEngine::Impl::PublishWall(const WallConsolidator::Wall& wall, ChangeFeed* feed,
                                     std::vector<Vec2>* moved_points,
                                     std::vector<ClusterId>* recounted) {
  const ClusterStats& stats = wall.stats();
  const ClusterStats::Fit& fit = wall.fit;
  // Its counts from the pieces' current statistics: a settled piece's copy in
  // the consolidator may be older.
  const WallCounts counts = CurrentCounts(wall.pieces);
  auto it = published_.find(stats.id);
  if (it == published_.end()) {
    feed->added.push_back(stats.id);
  } else {
    FusedFeature& old = it->second;
    if (old.fitted.a == fit.segment.a && old.fitted.b == fit.segment.b) {
      // A wall next to this Add's changes, or a settled one: at most its
      // counts changed, and the corner result stands.
      if (counts.Set(&old) || old.robots != stats.robots) {
        old.robots = stats.robots;
        recounted->push_back(stats.id);
      }
      return;
    }
    feed->updated.push_back(stats.id);
    moved_points->push_back(old.fitted.a);
    moved_points->push_back(old.fitted.b);
  }
  moved_points->push_back(fit.segment.a);
  moved_points->push_back(fit.segment.b);
  snapper_.Upsert(stats.id, fit.segment, fit.line);
  FusedFeature& fused = published_[stats.id] = stats.ToFused(fit);
  counts.Set(&fused);
}

std::optional<FusedFeature> FusionEngine::Impl::Get(ClusterId id) const {
  if (auto it = published_.find(id); it != published_.end()) return it->second;
  // A published cluster that consolidation folded into a wall of a smaller id.
  if (consolidator_.HasPiece(id)) return std::nullopt;
  auto node = node_of_.find(id);
  if (node == node_of_.end()) return std::nullopt;
  const uint32_t root = FindConst(node->second);
  if (MayCut(root)) {
    for (const std::vector<uint32_t>& group : GroupNodes(root)) {
      if (std::find(group.begin(), group.end(), node->second) == group.end()) continue;
      const ClusterStats stats = StatsOf(group);
      if (stats.id != id) return std::nullopt;  // a member, not the name of its group
      return stats.ToFused(stats.Refit());
    }
  }
  const ClusterStats& stats = *stats_[root];
  if (stats.id != id) return std::nullopt;  // a member, not the name of its cluster
  return stats.ToFused(stats.Refit());
}

FusionEngine::FusionEngine(const FusionParams& params) : impl_(std::make_unique<Impl>(params)) {}
FusionEngine::~FusionEngine() = default;
FusionEngine::FusionEngine(FusionEngine&&) noexcept = default;
FusionEngine& FusionEngine::operator=(FusionEngine&&) noexcept = default;

StatusOr<std::unique_ptr<FusionEngine>> FusionEngine::Create(const FusionParams& params) {
  MAPD_RETURN_IF_ERROR(params.Validate());
  return std::make_unique<FusionEngine>(params);
}

Status FusionEngine::Add(ObservationId observation, RobotId robot,
                         const std::vector<GroundFeature>& features, ChangeFeed* changes) {
  if (changes != nullptr) *changes = ChangeFeed();
  // Everything is checked before anything is touched: a refusal changes nothing.
  MAPD_RETURN_IF_ERROR(impl_->Validate(observation, features));
  impl_->Add(observation, robot, nullptr, features, changes);
  return Status::Ok();
}

Status FusionEngine::AddFrom(ObservationId observation, RobotId robot, const Vec2& sensor_xy_m,
                             const std::vector<GroundFeature>& features, ChangeFeed* changes) {
  if (changes != nullptr) *changes = ChangeFeed();
  if (!sensor_xy_m.allFinite() || sensor_xy_m.cwiseAbs().maxCoeff() > kMaxAbsCoordinateM) {
    return Status::InvalidArgument("sensor origin is not finite or beyond 1e6 m");
  }
  MAPD_RETURN_IF_ERROR(impl_->Validate(observation, features));
  impl_->Add(observation, robot, &sensor_xy_m, features, changes);
  return Status::Ok();
}

std::vector<FusedFeature> FusionEngine::Published() const {
  std::vector<FusedFeature> out;
  out.reserve(impl_->published_.size());
  for (const auto& [id, fused] : impl_->published_) out.push_back(fused);
  return out;
}

std::optional<FusedFeature> FusionEngine::Get(ClusterId id) const { return impl_->Get(id); }
std::optional<FusedFeature> FusionEngine::GetPublished(ClusterId id) const {
  auto it = impl_->published_.find(id);
  if (it == impl_->published_.end()) return std::nullopt;
  return it->second;
}
size_t FusionEngine::feature_count() const { return impl_->raw_feature_count_; }
size_t FusionEngine::node_count() const { return impl_->parent_.size(); }
size_t FusionEngine::cluster_count() const { return impl_->cluster_count_ + impl_->extra_groups_; }
size_t FusionEngine::published_count() const { return impl_->published_.size(); }
size_t FusionEngine::retired_count() const { return impl_->consolidator_.retired_count(); }

std::vector<FusedFeature> FusionEngine::Retired() const {
  std::vector<FusedFeature> out;
  for (ClusterId id : impl_->consolidator_.RetiredPieces()) {
    const ClusterStats& stats = impl_->consolidator_.pieces().at(id);
    FusedFeature retired = stats.ToFused(stats.Refit());
    impl_->CurrentCounts({id}).Set(&retired);  // a piece retired while settled
    out.push_back(std::move(retired));
  }
  return out;
}
size_t FusionEngine::largest_component_nodes() const {
  size_t largest = impl_->parent_.empty() ? 0 : 1;
  for (uint32_t n = 0; n < impl_->parent_.size(); ++n) {
    if (impl_->parent_[n] == n) largest = std::max<size_t>(largest, impl_->size_[n]);
  }
  return largest;
}
const FusionParams& FusionEngine::params() const { return impl_->params_; }

}  // namespace mapd::fusion

namespace mapd::fusion {

// Defined here because it needs Impl.
std::vector<std::vector<FeatureId>> EngineInspector::Partition(const FusionEngine& engine) {
  const FusionEngine::Impl& impl = *engine.impl_;
  std::unordered_map<uint32_t, std::vector<FeatureId>> by_root;
  for (const auto& [id, node] : impl.node_of_) by_root[impl.FindConst(node)].push_back(id);
  std::vector<std::vector<FeatureId>> out;
  for (auto& [root, members] : by_root) {
    if (impl.MayCut(root)) {  // the guard's groups, not the raw component
      for (const std::vector<uint32_t>& group : impl.GroupNodes(root)) {
        std::vector<FeatureId> ids;
        for (uint32_t node : group) ids.push_back(impl.anchors_[node].id);
        std::sort(ids.begin(), ids.end());
        out.push_back(std::move(ids));
      }
      continue;
    }
    std::sort(members.begin(), members.end());
    out.push_back(std::move(members));
  }
  std::sort(out.begin(), out.end());
  return out;
}

}  // namespace mapd::fusion
