// The 2D convex hull: collinear and interior points, degenerate inputs,
// extreme projections at a vertex.
#include "geometry/convex_hull2.h"

#include <gtest/gtest.h>

#include <random>

namespace mapd::geometry {
namespace {

TEST(ConvexHullTest, SquareWithInteriorAndCollinearPoints) {
  const std::vector<Vec2> hull =
      ConvexHull({{0, 0}, {1, 0}, {2, 0}, {2, 2}, {0, 2}, {1, 1}, {0, 1}, {2, 2}});
  ASSERT_EQ(hull.size(), 4u);
  EXPECT_EQ(hull[0], Vec2(0, 0));  // lowest-leftmost first, counter-clockwise
  EXPECT_EQ(hull[1], Vec2(2, 0));
  EXPECT_EQ(hull[2], Vec2(2, 2));
  EXPECT_EQ(hull[3], Vec2(0, 2));
}

TEST(ConvexHullTest, DegenerateInputs) {
  EXPECT_TRUE(ConvexHull({}).empty());
  EXPECT_EQ(ConvexHull({{1, 1}, {1, 1}}).size(), 1u);
  EXPECT_EQ(ConvexHull({{0, 0}, {1, 1}, {2, 2}, {3, 3}}).size(), 2u);  // collinear
}

TEST(ConvexHullTest, ExtremeProjectionIsAttainedAtAVertex) {
  std::mt19937 rng(3);
  std::normal_distribution<double> n(0.0, 1.0);
  std::vector<Vec2> points;
  for (int i = 0; i < 500; ++i) points.emplace_back(n(rng), 0.1 * n(rng));
  const std::vector<Vec2> hull = ConvexHull(points);
  for (double angle = 0.0; angle < 6.3; angle += 0.05) {
    const Vec2 d(std::cos(angle), std::sin(angle));
    double best_all = -1e300, best_hull = -1e300;
    for (const Vec2& p : points) best_all = std::max(best_all, p.dot(d));
    for (const Vec2& p : hull) best_hull = std::max(best_hull, p.dot(d));
    EXPECT_EQ(best_all, best_hull);
  }
}

// Strictly inside: left of every edge, so a point on an edge or a vertex is
// not; and the same answer as testing each edge in turn, on random hulls.
TEST(StrictlyInsideHullTest, InteriorOnlyAndEveryEdgeCounts) {
  const std::vector<Vec2> square = ConvexHull({{0, 0}, {2, 0}, {2, 2}, {0, 2}});
  EXPECT_TRUE(StrictlyInsideHull(square, {1, 1}));
  EXPECT_FALSE(StrictlyInsideHull(square, {1, 0})) << "on the first edge";
  EXPECT_FALSE(StrictlyInsideHull(square, {0, 1})) << "on the closing edge";
  EXPECT_FALSE(StrictlyInsideHull(square, {0, 0})) << "a vertex";
  EXPECT_FALSE(StrictlyInsideHull(square, {-0.1, 1})) << "beyond the closing edge only";
  EXPECT_FALSE(StrictlyInsideHull(square, {1, 2.1}));
  EXPECT_FALSE(StrictlyInsideHull({{0, 0}, {1, 1}}, {0.5, 0.5})) << "no area";
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> coord(-5.0, 5.0);
  for (int trial = 0; trial < 500; ++trial) {
    std::vector<Vec2> points;
    for (int i = 0; i < 3 + trial % 20; ++i) points.emplace_back(coord(rng), coord(rng));
    const std::vector<Vec2> hull = ConvexHull(points);
    for (int k = 0; k < 20; ++k) {
      const Vec2 p(coord(rng), coord(rng));
      bool left_of_all = hull.size() >= 3;
      for (size_t i = 0; i < hull.size(); ++i) {
        const Vec2 e = hull[(i + 1) % hull.size()] - hull[i], q = p - hull[i];
        left_of_all = left_of_all && e.x() * q.y() - e.y() * q.x() > 0.0;
      }
      ASSERT_EQ(StrictlyInsideHull(hull, p), left_of_all) << "trial " << trial;
    }
  }
}

}  // namespace
}  // namespace mapd::geometry
