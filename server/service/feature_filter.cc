#include "service/feature_filter.h"

#include <algorithm>

#include "geometry/segment2.h"

namespace mapd::service {

bool PolygonMeetsBox(const std::vector<Eigen::Vector3d>& boundary, const geometry::Box2& box) {
  const size_t n = boundary.size();
  if (n == 0) return false;
  for (size_t i = 0; i < n; ++i) {
    const geometry::Segment2 edge{boundary[i].head<2>(), boundary[(i + 1) % n].head<2>()};
    if (geometry::Intersects(edge, box)) return true;
  }
  // No edge meets the box: either the box is inside the polygon or apart.
  const geometry::Vec2 p = box.min;
  bool inside = false;  // even-odd rule, either orientation
  for (size_t i = 0, j = n - 1; i < n; j = i++) {
    const geometry::Vec2 a = boundary[i].head<2>(), b = boundary[j].head<2>();
    if ((a.y() > p.y()) != (b.y() > p.y()) &&
        p.x() < (b.x() - a.x()) * (p.y() - a.y()) / (b.y() - a.y()) + a.x()) {
      inside = !inside;
    }
  }
  return inside;
}

namespace {

bool HasRobot(const std::vector<std::string>& robots, const std::string& robot) {
  return robot.empty() || std::find(robots.begin(), robots.end(), robot) != robots.end();
}

}  // namespace

bool FeatureFilter::Matches(const FusedView& v) const {
  if (kind != KindFilter::kAny && kind != v.kind) return false;
  if (bbox && !geometry::Intersects(v.feature.segment, *bbox)) return false;
  return HasRobot(v.robots, robot);
}

bool FeatureFilter::Matches(const PlaneView& v) const {
  if (kind == KindFilter::kLine) return false;
  if (bbox && !PolygonMeetsBox(v.plane.boundary, *bbox)) return false;
  return HasRobot(v.robots, robot);
}

}  // namespace mapd::service
