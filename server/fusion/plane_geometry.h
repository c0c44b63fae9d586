// Geometry of the plane fusion criteria (plane_engine.h): sign-canonical
// normals, a 2D basis of a plane, and convex polygons in that basis (overlap
// area, gap). Pure functions on Eigen types.
#ifndef MAPD_FUSION_PLANE_GEOMETRY_H_
#define MAPD_FUSION_PLANE_GEOMETRY_H_

#include <Eigen/Core>
#include <vector>

#include "geometry/segment2.h"

namespace mapd::fusion {

// A plane normal's sign is arbitrary; this picks the one with a positive z
// (floors and ceilings both point up), else positive y, else positive x.
// REQUIRES: n is unit length.
Eigen::Vector3d CanonicalNormal(const Eigen::Vector3d& n);

// The angle between the lines of two unit normals, in [0, pi/2] radians
// (the sign of either normal does not matter).
double NormalAngle(const Eigen::Vector3d& a, const Eigen::Vector3d& b);

// An orthonormal basis (u, v) of the plane with unit normal n, a function of
// n alone (so the same normal always gives the same 2D coordinates).
struct PlaneBasis {
  Eigen::Vector3d u, v;
  static PlaneBasis Of(const Eigen::Vector3d& n);
  geometry::Vec2 Project(const Eigen::Vector3d& p) const { return {u.dot(p), v.dot(p)}; }
};

// The 2D convex hull (counter-clockwise about n) of `points` projected into `basis`.
std::vector<geometry::Vec2> ProjectedHull(const std::vector<Eigen::Vector3d>& points,
                                          const PlaneBasis& basis);

// Area of a simple polygon (positive when counter-clockwise), m^2.
double PolygonArea(const std::vector<geometry::Vec2>& polygon);

// The area of the intersection of two convex counter-clockwise polygons
// (Sutherland-Hodgman clipping), m^2. 0 when either has fewer than 3 vertices.
double ConvexIntersectionArea(const std::vector<geometry::Vec2>& a,
                              const std::vector<geometry::Vec2>& b);

// The distance between two convex counter-clockwise polygons (1 or 2 vertices
// allowed: a point, a segment), metres; 0 when they touch or overlap.
double ConvexPolygonGap(const std::vector<geometry::Vec2>& a, const std::vector<geometry::Vec2>& b);

// True if p lies in the convex counter-clockwise polygon or within margin_m of it.
bool NearConvexPolygon(const std::vector<geometry::Vec2>& polygon, const geometry::Vec2& p,
                       double margin_m);

}  // namespace mapd::fusion

#endif  // MAPD_FUSION_PLANE_GEOMETRY_H_
