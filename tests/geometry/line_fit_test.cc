// The total-least-squares line fit (Eq. 16-18): vertical and diagonal walls,
// mergeable moments, canonical direction, extreme projections.
#include "geometry/line_fit.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

namespace mapd::geometry {
namespace {

// The direction of `line` agrees with `expected` up to sign.
double AngleToAxis(const Line2& line, const Vec2& expected) {
  // asin of the cross product: accurate near 0, where acos of the dot is not.
  const Vec2 e = expected.normalized();
  return std::asin(
      std::min(1.0, std::abs(line.direction.x() * e.y() - line.direction.y() * e.x())));
}

TEST(LineFitTest, FitsVerticalWall) {
  PointMoments2 m;
  for (double y : {0.0, 1.0, 2.5, 7.0}) m.Add({3.0, y});
  const Line2 line = FitLine(m);
  EXPECT_NEAR(AngleToAxis(line, Vec2::UnitY()), 0.0, 1e-12);
  EXPECT_NEAR(line.point.x(), 3.0, 1e-12);
}

TEST(LineFitTest, FitsDiagonalWithSymmetricNoise) {
  PointMoments2 m;
  // Points at +-0.1 m either side of y = x: the TLS line is y = x exactly.
  for (double t : {0.0, 1.0, 2.0, 3.0}) {
    m.Add(Vec2(t, t) + 0.1 * Vec2(-1, 1).normalized());
    m.Add(Vec2(t, t) - 0.1 * Vec2(-1, 1).normalized());
  }
  const Line2 line = FitLine(m);
  EXPECT_NEAR(AngleToAxis(line, Vec2(1, 1)), 0.0, 1e-12);
  EXPECT_NEAR(line.point.x(), 1.5, 1e-12);
  EXPECT_NEAR(line.point.y(), 1.5, 1e-12);
}

TEST(LineFitTest, MergeEqualsAddingAllPoints) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-5.0, 5.0);
  PointMoments2 all, left, right;
  for (int i = 0; i < 50; ++i) {
    const Vec2 p(1e5 + u(rng), -2e5 + 0.1 * u(rng));  // far from the origin on purpose
    all.Add(p);
    (i % 3 == 0 ? left : right).Add(p);
  }
  left.Merge(right);
  EXPECT_EQ(left.count, all.count);
  EXPECT_NEAR((left.mean - all.mean).norm(), 0.0, 1e-9);
  EXPECT_NEAR((left.scatter - all.scatter).norm(), 0.0, 1e-9 * all.scatter.norm());
}

TEST(LineFitTest, MergeWithEmptyIsIdentity) {
  PointMoments2 a, empty;
  a.Add({1, 2});
  a.Add({3, 4});
  PointMoments2 b = a;
  b.Merge(empty);
  EXPECT_EQ(b.count, 2u);
  EXPECT_EQ(b.mean, a.mean);
  empty.Merge(a);
  EXPECT_EQ(empty.scatter, a.scatter);
}

TEST(LineFitTest, CanonicalDirectionIgnoresSign) {
  for (double angle = 0.0; angle < 6.28; angle += 0.1) {
    const Vec2 d(std::cos(angle), std::sin(angle));
    EXPECT_EQ(CanonicalDirection(d), CanonicalDirection(-d));
  }
}

TEST(LineFitTest, ExtremeProjectionsSpanThePoints) {
  const Line2 line{{0, 0}, {1, 0}};
  const std::vector<Vec2> points = {{2, 1}, {-1, -1}, {5, 0.5}};
  const Segment2 s = ExtremeProjections(line, points);
  EXPECT_EQ(s.a, Vec2(-1, 0));
  EXPECT_EQ(s.b, Vec2(5, 0));
}

}  // namespace
}  // namespace mapd::geometry
