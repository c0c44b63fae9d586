// Which published features and planes a reader asked for: the filters of
// GetFeatureMap (bbox, kind) and WatchFeatureMap (those and a robot), as one
// predicate so that both RPCs agree on what is in the map they serve.
#ifndef MAPD_SERVICE_FEATURE_FILTER_H_
#define MAPD_SERVICE_FEATURE_FILTER_H_

#include <Eigen/Core>
#include <optional>
#include <string>
#include <vector>

#include "geometry/box2.h"
#include "service/core.h"

namespace mapd::service {

// Whether the closed polygon (the ground projection of a plane's boundary)
// meets the box: an edge crosses it, or the box lies inside the polygon.
bool PolygonMeetsBox(const std::vector<Eigen::Vector3d>& boundary, const geometry::Box2& box);

struct FeatureFilter {
  std::optional<geometry::Box2> bbox;  // the segment (plane: boundary's projection) meets it
  KindFilter kind = KindFilter::kAny;  // kLine leaves every plane out
  std::string robot;                   // among the contributors; empty = any

  bool Matches(const FusedView& v) const;
  bool Matches(const PlaneView& v) const;
};

}  // namespace mapd::service

#endif  // MAPD_SERVICE_FEATURE_FILTER_H_
