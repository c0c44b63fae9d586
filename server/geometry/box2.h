// Axis-aligned boxes in the ground plane (metres).
#ifndef MAPD_GEOMETRY_BOX2_H_
#define MAPD_GEOMETRY_BOX2_H_

#include <algorithm>

#include "geometry/segment2.h"

namespace mapd::geometry {

struct Box2 {
  Vec2 min = Vec2::Zero();
  Vec2 max = Vec2::Zero();

  bool Contains(const Vec2& p) const {
    return p.x() >= min.x() && p.x() <= max.x() && p.y() >= min.y() && p.y() <= max.y();
  }
};

// True when any point of the closed segment lies in the closed box
// (Liang-Barsky clipping of the segment's parameter range).
inline bool Intersects(const Segment2& s, const Box2& box) {
  double t0 = 0.0, t1 = 1.0;
  const Vec2 d = s.direction();
  for (int axis = 0; axis < 2; ++axis) {
    if (d[axis] == 0.0) {
      if (s.a[axis] < box.min[axis] || s.a[axis] > box.max[axis]) return false;
      continue;
    }
    double ta = (box.min[axis] - s.a[axis]) / d[axis];
    double tb = (box.max[axis] - s.a[axis]) / d[axis];
    if (ta > tb) std::swap(ta, tb);
    t0 = std::max(t0, ta);
    t1 = std::min(t1, tb);
    if (t0 > t1) return false;
  }
  return true;
}

}  // namespace mapd::geometry

#endif  // MAPD_GEOMETRY_BOX2_H_
