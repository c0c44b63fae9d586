#include "fusion/corner_snap.h"

#include <algorithm>
#include <cmath>
#include <tuple>

namespace mapd::fusion {

using geometry::Line2;
using geometry::Segment2;
using geometry::Vec2;

namespace {

// Grid cells are 2 * snap_m wide, the engine's invalidation radius, so that
// queries probe 3 x 3 cells at most; but no smaller than this, so that a tiny
// snap distance does not blow up the cell indices. Queries filter by distance.
constexpr double kMinCellM = 1e-3;

double Cross(const Vec2& u, const Vec2& v) { return u.x() * v.y() - u.y() * v.x(); }

}  // namespace

Vec2 CornerPoint(const Vec2& p, const Line2& lp, const Vec2& q, const Line2& lq, double snap_m,
                 CornerMode mode) {
  const Vec2 midpoint = 0.5 * (p + q);
  if (mode == CornerMode::kMidpoint) return midpoint;
  const double sin_angle = Cross(lp.direction, lq.direction);  // unit directions
  if (std::abs(sin_angle) <= std::sin(kMinCornerAngleRad)) return midpoint;
  // lp.point + t lp.direction = lq.point + s lq.direction, solved for t.
  const double t = Cross(lq.point - lp.point, lq.direction) / sin_angle;
  const Vec2 x = lp.point + t * lp.direction;
  if ((x - p).norm() > snap_m || (x - q).norm() > snap_m) return midpoint;
  return x;
}

CornerSnapper::CornerSnapper(double snap_m, CornerMode mode)
    : snap_m_(snap_m), mode_(mode), grid_(std::max(2.0 * snap_m, kMinCellM)) {}

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

bool CornerSnapper::Nearest(ClusterId id, const Vec2& p, EndRef* nearest) const {
  bool found = false;
  double best_m = 0.0;
  grid_.ForEachNear(p, snap_m_, [&](const EndRef& r) {
    if (r.id == id) return;
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

Segment2 CornerSnapper::Snapped(ClusterId id) const {
  const Entry& self = entries_.at(id);
  Segment2 out = self.fitted;
  if (snap_m_ <= 0.0) return out;
  EndRef partner[2];
  bool paired[2] = {false, false};
  for (int end = 0; end < 2; ++end) {
    EndRef back;
    paired[end] = Nearest(id, EndOf(self, end), &partner[end]) &&
                  Nearest(partner[end].id, partner[end].p, &back) && back.id == id &&
                  back.end == end;  // mutual
  }
  // Both ends paired with the same feature: no corner, two views of one
  // short stretch; snapping would publish them as one segment twice.
  if (paired[0] && paired[1] && partner[0].id == partner[1].id) return out;
  for (int end = 0; end < 2; ++end) {
    if (!paired[end]) continue;
    const Vec2& p = EndOf(self, end);
    const EndRef& other = partner[end];
    const Entry& peer = entries_.at(other.id);
    // Evaluate in (cluster id) order so that both partners get the same point.
    const Vec2 joint = id < other.id
                           ? CornerPoint(p, self.line, other.p, peer.line, snap_m_, mode_)
                           : CornerPoint(other.p, peer.line, p, self.line, snap_m_, mode_);
    (end == 0 ? out.a : out.b) = joint;
  }
  return out;
}

}  // namespace mapd::fusion
