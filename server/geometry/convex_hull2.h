// 2D convex hull (Andrew's monotone chain).
#ifndef MAPD_GEOMETRY_CONVEX_HULL2_H_
#define MAPD_GEOMETRY_CONVEX_HULL2_H_

#include <vector>

#include "geometry/segment2.h"

namespace mapd::geometry {

// The vertices of the convex hull of `points`, counter-clockwise, without
// duplicates or collinear points; 0, 1 or 2 points for degenerate input. O(n log n).
// Why fusion wants it: the extreme projection of a point set along any direction
// is attained at a hull vertex, so a cluster keeps its hull instead of all points.
std::vector<Vec2> ConvexHull(std::vector<Vec2> points);

// True if p lies strictly inside `hull` (a ConvexHull() result of at least 3
// vertices), so that adding p leaves the hull as it is. O(h).
bool StrictlyInsideHull(const std::vector<Vec2>& hull, const Vec2& p);

}  // namespace mapd::geometry

#endif  // MAPD_GEOMETRY_CONVEX_HULL2_H_
