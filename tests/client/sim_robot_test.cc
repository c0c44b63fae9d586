// The simulated laser robot of the demo and `mapctl simulate`: seeded batches,
// ray casting, segments extracted on the true walls.
#include "client/sim_robot.h"

#include <gtest/gtest.h>

#include <cmath>

namespace mapd::client {
namespace {

namespace pb = mapserver::v1;

SimRobotParams Params(uint64_t seed) {
  SimRobotParams p;
  p.robot_id = "r1";
  p.session_id = "s1";
  p.seed = seed;
  return p;
}

// Sensor-frame point -> map frame, with the batch's pose (a yaw quaternion).
Vec2 ToMap(const pb::ObservationBatch& batch, const pb::Vec3& p) {
  const auto& t = batch.t_frame_sensor().translation();
  const auto& q = batch.t_frame_sensor().rotation();
  const double yaw = 2 * std::atan2(q.z(), q.w());
  return {t.x() + std::cos(yaw) * p.x() - std::sin(yaw) * p.y(),
          t.y() + std::sin(yaw) * p.x() + std::cos(yaw) * p.y()};
}

double DistanceToWorld(const Vec2& p, const SimWorld& world) {
  double best = INFINITY;
  for (const Segment2& w : world.walls) best = std::min(best, geometry::PointSegmentDistance(p, w));
  return best;
}

TEST(SimRobotTest, SameSeedGivesSameBatches) {
  SimRobot a(DefaultWorld(), Params(5));
  SimRobot b(DefaultWorld(), Params(5));
  SimRobot c(DefaultWorld(), Params(6));
  bool any_difference = false;
  for (int i = 0; i < 20; ++i) {
    const pb::ObservationBatch ba = a.NextBatch();
    EXPECT_EQ(ba.SerializeAsString(), b.NextBatch().SerializeAsString()) << "scan " << i;
    any_difference |= ba.SerializeAsString() != c.NextBatch().SerializeAsString();
  }
  EXPECT_TRUE(any_difference);
}

TEST(SimRobotTest, BatchesCarryIdsSeqAndUnitYawPose) {
  SimRobotParams p = Params(1);
  p.first_seq = 10;
  SimRobot robot(DefaultWorld(), p);
  for (uint64_t i = 0; i < 5; ++i) {
    const pb::ObservationBatch batch = robot.NextBatch();
    EXPECT_EQ(batch.robot_id(), "r1");
    EXPECT_EQ(batch.session_id(), "s1");
    EXPECT_EQ(batch.seq(), 10 + i);
    const auto& q = batch.t_frame_sensor().rotation();
    EXPECT_NEAR(q.w() * q.w() + q.z() * q.z(), 1.0, 1e-12);
    EXPECT_EQ(q.x(), 0);
    EXPECT_EQ(q.y(), 0);
    for (const auto& line : batch.lines()) {
      EXPECT_EQ(line.a().z(), 0);
      EXPECT_EQ(line.b().z(), 0);
    }
  }
}

// Over a whole loop, every extracted segment lies on a true wall: both
// endpoints within 0.1 m of one, and no segment is shorter than 0.3 m.
TEST(SimRobotTest, ExtractedSegmentsLieOnTrueWalls) {
  SimRobot robot(DefaultWorld(), Params(3));
  size_t segments = 0;
  for (int scan = 0; scan < 180; ++scan) {  // 36 m loop, 0.2 m steps
    const pb::ObservationBatch batch = robot.NextBatch();
    EXPECT_GE(batch.lines_size(), 2) << "scan " << scan;
    for (const auto& line : batch.lines()) {
      const Vec2 a = ToMap(batch, line.a()), b = ToMap(batch, line.b());
      EXPECT_LT(DistanceToWorld(a, robot.world()), 0.1)
          << "scan " << scan << " a " << a.transpose();
      EXPECT_LT(DistanceToWorld(b, robot.world()), 0.1)
          << "scan " << scan << " b " << b.transpose();
      // The midpoint too: a segment must not bridge two walls.
      EXPECT_LT(DistanceToWorld((a + b) / 2, robot.world()), 0.1) << "scan " << scan;
      EXPECT_GE((b - a).norm(), 0.3);
      ++segments;
    }
  }
  EXPECT_GT(segments, 180u * 3);
}

TEST(ExtractSegmentsTest, OneStraightWallGivesOneSegment) {
  // A wall at x = 2 in front of the sensor, no noise.
  const std::vector<Segment2> walls = {{{2, -3}, {2, 3}}};
  LaserParams laser;
  laser.range_noise_m = 0;
  std::mt19937_64 rng(1);
  const std::vector<double> ranges = CastScan(walls, Pose2{}, laser, &rng);
  const std::vector<Segment2> segments = ExtractSegments(ranges, laser, ExtractionParams{});
  ASSERT_EQ(segments.size(), 1u);
  EXPECT_NEAR(segments[0].a.x(), 2, 1e-6);
  EXPECT_NEAR(segments[0].b.x(), 2, 1e-6);
  EXPECT_GT(std::abs(segments[0].b.y() - segments[0].a.y()), 5.0);
}

TEST(ExtractSegmentsTest, CornerSplitsIntoTwo) {
  const std::vector<Segment2> walls = {{{3, -4}, {3, 1}}, {{3, 1}, {-3, 1}}};
  LaserParams laser;
  std::mt19937_64 rng(2);
  const std::vector<Segment2> segments =
      ExtractSegments(CastScan(walls, Pose2{}, laser, &rng), laser, {});
  ASSERT_EQ(segments.size(), 2u);
  for (const Segment2& s : segments) {
    EXPECT_LT(std::min(geometry::PointSegmentDistance(s.a, walls[0]),
                       geometry::PointSegmentDistance(s.a, walls[1])),
              0.05);
    EXPECT_LT(std::min(geometry::PointSegmentDistance(s.b, walls[0]),
                       geometry::PointSegmentDistance(s.b, walls[1])),
              0.05);
  }
}

TEST(CastScanTest, BeamsWithoutAWallAreNaN) {
  const std::vector<Segment2> walls = {{{2, -1}, {2, 1}}};
  LaserParams laser;
  std::mt19937_64 rng(1);
  const std::vector<double> ranges = CastScan(walls, Pose2{}, laser, &rng);
  ASSERT_EQ(ranges.size(), 180u);
  EXPECT_TRUE(std::isnan(ranges.front()));                          // pointing along -y
  EXPECT_NEAR(ranges[89], 2.0 / std::cos(0.5 * M_PI / 179), 0.05);  // about straight ahead
}

}  // namespace
}  // namespace mapd::client
