#include "eval/baselines/batch_fuser.h"

#include <algorithm>
#include <cmath>
#include <string>
#include <utility>

#include "fusion/corner_snap.h"

namespace mapd::fusion::baselines {

using geometry::Segment2;
using geometry::Vec2;

namespace {

constexpr double kMaxAbsCoordinateM = 1e6;  // as the engine
constexpr double kMinSegmentLengthM = 1e-9;

bool Same(const FusedFeature& a, const FusedFeature& b) {
  return a.segment.a == b.segment.a && a.segment.b == b.segment.b && a.support == b.support &&
         a.member_count == b.member_count;
}

}  // namespace

Status BatchFuser::Add(ObservationId observation, RobotId robot,
                       const std::vector<GroundFeature>& features, ChangeFeed* changes) {
  if (changes != nullptr) *changes = ChangeFeed();
  if (observations_.count(observation) != 0) {
    return Status::InvalidArgument("observation " + std::to_string(observation) +
                                   " was added before");
  }
  std::unordered_set<FeatureId> batch;
  for (size_t i = 0; i < features.size(); ++i) {
    const Segment2& s = features[i].segment;
    const std::string name = "features[" + std::to_string(i) + "]";
    if (!s.a.allFinite() || !s.b.allFinite() || s.a.cwiseAbs().maxCoeff() > kMaxAbsCoordinateM ||
        s.b.cwiseAbs().maxCoeff() > kMaxAbsCoordinateM) {
      return Status::InvalidArgument(name + " is not finite or beyond 1e6 m");
    }
    if (!(s.length() >= kMinSegmentLengthM))
      return Status::InvalidArgument(name + " has zero length");
    if (feature_ids_.count(features[i].id) != 0 || !batch.insert(features[i].id).second) {
      return Status::InvalidArgument(name + ": feature id " + std::to_string(features[i].id) +
                                     " is not unique");
    }
  }
  std::vector<FusedFeature> before;
  if (changes != nullptr) before = Published();
  observations_.insert(observation);
  for (const GroundFeature& f : features) {
    feature_ids_.insert(f.id);
    members_.push_back({f, observation, robot});
  }
  dirty_ = true;
  if (changes == nullptr) return Status::Ok();
  // Batch methods have no incremental state: diff the whole map.
  const std::vector<FusedFeature> after = Published();
  std::map<ClusterId, const FusedFeature*> old_by_id;
  for (const FusedFeature& f : before) old_by_id[f.id] = &f;
  for (const FusedFeature& f : after) {
    auto it = old_by_id.find(f.id);
    if (it == old_by_id.end()) {
      changes->added.push_back(f.id);
    } else {
      if (!Same(*it->second, f)) changes->updated.push_back(f.id);
      old_by_id.erase(it);
    }
  }
  for (const auto& [id, f] : old_by_id) changes->removed.push_back(id);
  return Status::Ok();
}

std::vector<FusedFeature> BatchFuser::Published() const {
  if (dirty_) {
    cache_ = Compute();
    dirty_ = false;
  }
  return cache_;
}

std::vector<FusedFeature> BatchFuser::Compute() const {
  std::vector<FusedFeature> out;
  CornerSnapper snapper(post_.snap_m, post_.corner_mode);
  for (const std::vector<uint32_t>& cluster : Cluster(members_)) {
    if (cluster.empty()) continue;
    std::unordered_set<ObservationId> support;
    for (uint32_t i : cluster) support.insert(members_[i].observation);
    if (support.size() < post_.min_support) continue;
    const geometry::Line2 line = MergeLine(members_, cluster);
    std::vector<Vec2> ends;
    ends.reserve(2 * cluster.size());
    FusedFeature f;
    f.id = members_[cluster.front()].feature.id;
    f.z_min_m = members_[cluster.front()].feature.z_min_m;
    f.z_max_m = members_[cluster.front()].feature.z_max_m;
    for (uint32_t i : cluster) {
      const Member& m = members_[i];
      ends.push_back(m.feature.segment.a);
      ends.push_back(m.feature.segment.b);
      f.id = std::min(f.id, m.feature.id);
      f.z_min_m = std::min(f.z_min_m, m.feature.z_min_m);
      f.z_max_m = std::max(f.z_max_m, m.feature.z_max_m);
      if (m.feature.origin == FeatureOrigin::kPlane) ++f.plane_members;
      f.robots.push_back(m.robot);
    }
    std::sort(f.robots.begin(), f.robots.end());
    f.robots.erase(std::unique(f.robots.begin(), f.robots.end()), f.robots.end());
    f.fitted = geometry::ExtremeProjections(line, ends);
    f.segment = f.fitted;
    f.support = static_cast<uint32_t>(support.size());
    f.member_count = static_cast<uint32_t>(cluster.size());
    snapper.Upsert(f.id, f.fitted, line);
    out.push_back(std::move(f));
  }
  for (FusedFeature& f : out) f.segment = snapper.Snapped(f.id);
  std::sort(out.begin(), out.end(),
            [](const FusedFeature& a, const FusedFeature& b) { return a.id < b.id; });
  return out;
}

std::vector<std::vector<uint32_t>> BatchFuser::OrientationGroups(
    const std::vector<Member>& members, const OrientationShiftParams& params) {
  std::vector<double> theta(members.size());
  const std::vector<double> weights(members.size(), 1.0);
  for (size_t i = 0; i < members.size(); ++i) theta[i] = AxialAngle(members[i].feature.segment);
  const Modes orientation = OrientationModes(theta, weights, params);
  std::vector<std::vector<uint32_t>> by_mode(orientation.mode.size());
  for (size_t i = 0; i < members.size(); ++i) {
    by_mode[orientation.label[i]].push_back(static_cast<uint32_t>(i));
  }
  return by_mode;
}

}  // namespace mapd::fusion::baselines
