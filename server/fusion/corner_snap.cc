#include "fusion/corner_snap.h"

#include <algorithm>
#include <cmath>
#include <set>
#include <tuple>

namespace mapd::fusion {

using geometry::Cross;
using geometry::Line2;
using geometry::Segment2;
using geometry::Vec2;

namespace {

// Grid cells are 2 * snap_m wide, the engine's invalidation radius, so that
// queries probe 3 x 3 cells at most; but no smaller than this, so that a tiny
// snap distance does not blow up the cell indices. Queries filter by distance.
constexpr double kMinCellM = 1e-3;

}  // namespace

CornerJoint CornerPoint(const Vec2& p, const Line2& lp, const Vec2& q, const Line2& lq,
                        double snap_m, CornerMode mode) {
  const CornerJoint midpoint{0.5 * (p + q), false};
  if (mode == CornerMode::kMidpoint) return midpoint;
  const double sin_angle = Cross(lp.direction, lq.direction);  // unit directions
  if (std::abs(sin_angle) <= std::sin(kMinCornerAngleRad)) return midpoint;
  // lp.point + t lp.direction = lq.point + s lq.direction, solved for t.
  const double t = Cross(lq.point - lp.point, lq.direction) / sin_angle;
  const Vec2 x = lp.point + t * lp.direction;
  if ((x - p).norm() > snap_m || (x - q).norm() > snap_m) return midpoint;
  return {x, true};
}

CornerSnapper::CornerSnapper(double snap_m, CornerMode mode, CornerPairing pairing)
    : snap_m_(snap_m), mode_(mode), pairing_(pairing), grid_(std::max(2.0 * snap_m, kMinCellM)) {}

void CornerSnapper::Upsert(ClusterId id, const Segment2& fitted, const Line2& line) {
  Erase(id);
  entries_[id] = {fitted, line};
  grid_.Insert(fitted.a, {id, 0, fitted.a});
  grid_.Insert(fitted.b, {id, 1, fitted.b});
}

bool CornerSnapper::Lookup(ClusterId id, Segment2* fitted, Line2* line) const {
  auto it = entries_.find(id);
  if (it == entries_.end()) return false;
  *fitted = it->second.fitted;
  *line = it->second.line;
  return true;
}

void CornerSnapper::Erase(ClusterId id) {
  auto it = entries_.find(id);
  if (it == entries_.end()) return;
  const auto same_id = [id](const EndRef& r) { return r.id == id; };
  grid_.EraseIf(it->second.fitted.a, same_id);
  grid_.EraseIf(it->second.fitted.b, same_id);
  entries_.erase(it);
}

void CornerSnapper::CollectNear(const Vec2& p, double radius_m, std::vector<ClusterId>* ids) const {
  grid_.ForEachNear(p, radius_m, [&](const EndRef& r) {
    if ((r.p - p).norm() <= radius_m) ids->push_back(r.id);
  });
}

template <typename Skip>
bool CornerSnapper::Nearest(ClusterId id, const Vec2& p, Skip skip, EndRef* nearest) const {
  bool found = false;
  double best_m = 0.0;
  grid_.ForEachNear(p, snap_m_, [&](const EndRef& r) {
    if (r.id == id || skip(r)) return;
    const double d = (r.p - p).norm();
    if (!(d < snap_m_)) return;
    if (!found || std::tie(d, r.id, r.end) < std::tie(best_m, nearest->id, nearest->end)) {
      found = true;
      best_m = d;
      *nearest = r;
    }
  });
  return found;
}

Vec2 CornerSnapper::Joint(const EndRef& e, const EndRef& other) const {
  const Line2& le = entries_.at(e.id).line;
  const Line2& lo = entries_.at(other.id).line;
  // Evaluate in (cluster id) order so that both partners get the same point.
  const CornerJoint joint = e.id < other.id ? CornerPoint(e.p, le, other.p, lo, snap_m_, mode_)
                                            : CornerPoint(other.p, lo, e.p, le, snap_m_, mode_);
  if (mode_ == CornerMode::kMidpoint || joint.intersection) return joint.point;
  // No usable intersection: the foot of the midpoint on e's own line.
  return le.point + (joint.point - le.point).dot(le.direction) * le.direction;
}

void CornerSnapper::CollectAffected(const std::vector<Vec2>& points, double slack_m,
                                    std::vector<ClusterId>* ids) const {
  if (snap_m_ <= 0.0) return;
  if (pairing_ == CornerPairing::kMutualNearest) {
    for (const Vec2& p : points) CollectNear(p, 2.0 * snap_m_ + slack_m, ids);
    return;
  }
  // Greedy: every component that had or has an endpoint next to a point. A
  // vanished endpoint's old component now falls into parts, each with an
  // endpoint within snap_m of where it was.
  std::set<EndKey> seen;
  for (const Vec2& p : points) {
    std::vector<EndRef> seeds;
    grid_.ForEachNear(p, snap_m_ + slack_m, [&](const EndRef& r) {
      if ((r.p - p).norm() <= snap_m_ + slack_m) seeds.push_back(r);
    });
    for (const EndRef& seed : seeds) {
      if (seen.count({seed.id, seed.end})) continue;
      for (const EndRef& r : Component(seed)) {
        seen.insert({r.id, r.end});
        ids->push_back(r.id);
      }
    }
  }
}

std::vector<CornerSnapper::EndRef> CornerSnapper::Component(const EndRef& seed) const {
  std::set<EndKey> in{{seed.id, seed.end}};
  std::vector<EndRef> out{seed};
  for (size_t k = 0; k < out.size(); ++k) {  // breadth first; out grows
    const EndRef e = out[k];
    grid_.ForEachNear(e.p, snap_m_, [&](const EndRef& r) {
      if (r.id == e.id || !((r.p - e.p).norm() < snap_m_)) return;
      if (in.insert({r.id, r.end}).second) out.push_back(r);
    });
  }
  std::sort(out.begin(), out.end(), [](const EndRef& x, const EndRef& y) {
    return std::tie(x.id, x.end) < std::tie(y.id, y.end);
  });
  return out;
}

void CornerSnapper::SolveGreedy(const std::vector<EndRef>& component,
                                std::map<EndKey, EndRef>* partner) const {
  std::set<EndKey> paired;
  const auto taken = [&](const EndRef& r) { return paired.count({r.id, r.end}) > 0; };
  for (const EndRef& e : component) {  // (id, end) order
    if (taken(e)) continue;
    EndRef other;
    if (!Nearest(e.id, e.p, taken, &other)) continue;
    paired.insert({e.id, e.end});
    paired.insert({other.id, other.end});
    (*partner)[{e.id, e.end}] = other;
    (*partner)[{other.id, other.end}] = e;
  }
}

std::vector<Segment2> CornerSnapper::SnappedAll(const std::vector<ClusterId>& ids) const {
  std::vector<Segment2> out;
  out.reserve(ids.size());
  std::set<EndKey> solved;            // greedy: endpoints whose component is solved
  std::map<EndKey, EndRef> partners;  // greedy: their partners, if paired
  const auto none = [](const EndRef&) { return false; };
  // The endpoint e snaps with, by the pairing rule; false if none.
  const auto partner_of = [&](const EndRef& e, EndRef* other) {
    if (pairing_ == CornerPairing::kMutualNearest) {
      EndRef back;
      return Nearest(e.id, e.p, none, other) && Nearest(other->id, other->p, none, &back) &&
             back.id == e.id && back.end == e.end;
    }
    if (!solved.count({e.id, e.end})) {
      const std::vector<EndRef> component = Component(e);
      for (const EndRef& r : component) solved.insert({r.id, r.end});
      SolveGreedy(component, &partners);
    }
    auto it = partners.find({e.id, e.end});
    if (it == partners.end()) return false;
    *other = it->second;
    return true;
  };
  for (ClusterId id : ids) {
    const Entry& self = entries_.at(id);
    Segment2 s = self.fitted;
    if (snap_m_ > 0.0) {
      EndRef partner[2];
      bool paired[2];
      for (int end = 0; end < 2; ++end)
        paired[end] = partner_of({id, end, EndOf(self, end)}, &partner[end]);
      // Both ends paired with the same feature: no corner, two views of one
      // short stretch; snapping would publish them as one segment twice.
      const bool twin = paired[0] && paired[1] && partner[0].id == partner[1].id;
      for (int end = 0; end < 2 && !twin; ++end) {
        if (paired[end]) (end == 0 ? s.a : s.b) = Joint({id, end, EndOf(self, end)}, partner[end]);
      }
    }
    out.push_back(s);
  }
  return out;
}

}  // namespace mapd::fusion
