#include "bench/seen_through.h"

#include <algorithm>
#include <cmath>

namespace mapd::bench {

using geometry::Segment2;
using geometry::Vec2;

SeenThroughGrid::SeenThroughGrid(const std::vector<BeamFan>& fans) {
  // A dense grid over everything the counted beams touch (a building at 10 cm
  // is a few million cells).
  Vec2 lo(1e300, 1e300), hi(-1e300, -1e300);
  for (size_t f = 0; f < fans.size(); f += 2) {
    lo = lo.cwiseMin(fans[f].origin_m);
    hi = hi.cwiseMax(fans[f].origin_m);
    for (const Vec2& p : *fans[f].hits_m) {
      lo = lo.cwiseMin(p);
      hi = hi.cwiseMax(p);
    }
  }
  if (lo.x() > hi.x()) return;
  lo_ = lo - Vec2(kCellM, kCellM);
  width_ = static_cast<int64_t>(std::ceil((hi.x() - lo_.x()) / kCellM)) + 2;
  height_ = static_cast<int64_t>(std::ceil((hi.y() - lo_.y()) / kCellM)) + 2;
  passes_.assign(static_cast<size_t>(width_ * height_), 0);
  hits_.assign(passes_.size(), 0);
  for (size_t f = 0; f < fans.size(); f += 2) {
    const Vec2& o = fans[f].origin_m;
    for (const Vec2& p : *fans[f].hits_m) {
      ++hits_[static_cast<size_t>(Index(p))];
      const Vec2 d = p - o;
      const double range = d.norm();
      const double stop = range - kStopBeforeHitM;
      if (!(stop >= 0.0)) continue;
      const Vec2 u = d / range;
      for (double t = 0.0; t <= stop; t += kPassStepM) {
        ++passes_[static_cast<size_t>(Index(o + t * u))];
      }
    }
  }
}

int64_t SeenThroughGrid::Index(const Vec2& p) const {
  const auto cx = static_cast<int64_t>(std::floor((p.x() - lo_.x()) / kCellM));
  const auto cy = static_cast<int64_t>(std::floor((p.y() - lo_.y()) / kCellM));
  if (cx < 0 || cy < 0 || cx >= width_ || cy >= height_) return -1;
  return cy * width_ + cx;
}

bool SeenThroughGrid::SeenThrough(const Vec2& p) const {
  const int64_t i = Index(p);
  if (i < 0) return false;
  const uint32_t passes = passes_[static_cast<size_t>(i)];
  return passes >= kMinPasses && passes >= kPassesPerHit * hits_[static_cast<size_t>(i)];
}

double SeenThroughGrid::SeenThroughLength(const Segment2& s) const {
  const double length = s.length();
  if (!(length > 0.0)) return 0.0;
  const int steps = std::max(1, static_cast<int>(std::ceil(length / kSegmentStepM)));
  const double step = length / steps;
  double seen = 0.0;
  for (int i = 0; i < steps; ++i) {
    const double t = (static_cast<double>(i) + 0.5) / steps;
    if (SeenThrough(s.a + t * (s.b - s.a))) seen += step;
  }
  return seen;
}

SeenThroughGrid::Totals SeenThroughGrid::Measure(const std::vector<Segment2>& segments) const {
  Totals t;
  for (const Segment2& s : segments) {
    t.published_m += s.length();
    t.seen_through_m += SeenThroughLength(s);
  }
  return t;
}

}  // namespace mapd::bench
