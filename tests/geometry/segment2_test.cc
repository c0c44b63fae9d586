// Point-to-segment distance, clamped to the endpoints and for degenerate segments.
#include "geometry/segment2.h"

#include <gtest/gtest.h>

namespace mapd::geometry {
namespace {

TEST(PointSegmentDistanceTest, ClampsToEndpoints) {
  const Segment2 s{{0, 0}, {2, 0}};
  EXPECT_DOUBLE_EQ(PointSegmentDistance({1, 1}, s), 1.0);   // perpendicular foot inside
  EXPECT_DOUBLE_EQ(PointSegmentDistance({3, 0}, s), 1.0);   // beyond b
  EXPECT_DOUBLE_EQ(PointSegmentDistance({-3, 4}, s), 5.0);  // beyond a
}

TEST(PointSegmentDistanceTest, DegenerateSegmentIsAPoint) {
  const Segment2 s{{1, 1}, {1, 1}};
  EXPECT_DOUBLE_EQ(PointSegmentDistance({4, 5}, s), 5.0);
}

}  // namespace
}  // namespace mapd::geometry
