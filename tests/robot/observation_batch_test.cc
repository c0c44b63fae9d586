// A scan's ObservationBatch: the header, the sensor pose and the stamp passed
// through, the lines in the sensor frame at z = 0, and what the server would
// refuse refused here first with the field named.
#include "client/robot/observation_batch.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>

namespace mapd::robot {
namespace {

namespace pb = mapserver::v1;

BatchHeader Header() {
  BatchHeader h;
  h.robot_id = "r1";
  h.session_id = "s1";
  h.seq = 7;
  h.stamp_ns = 1'700'000'000'123'456'789;
  return h;
}

Eigen::Isometry3d Pose() {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  T.translation() = Eigen::Vector3d(4.0, -2.5, 0.4);
  return T;
}

// A wall 2 m ahead, 21 beams over +-10 deg.
LaserScan WallScan() {
  LaserScan scan;
  scan.angle_min_rad = -10 * M_PI / 180;
  scan.angle_increment_rad = M_PI / 180;
  scan.range_max_m = 20;
  for (int i = 0; i <= 20; ++i)
    scan.ranges_m.push_back(2.0 / std::cos(scan.angle_min_rad + i * scan.angle_increment_rad));
  return scan;
}

TEST(ObservationBatchTest, CarriesTheHeaderPoseStampAndLines) {
  BatchHeader header = Header();
  header.frame = pb::SESSION_FRAME_LOCAL;
  const auto batch = ScanBatch(header, Pose(), WallScan(), LineExtractionParams());
  ASSERT_TRUE(batch.ok()) << batch.status().message();
  EXPECT_EQ(batch->robot_id(), "r1");
  EXPECT_EQ(batch->session_id(), "s1");
  EXPECT_EQ(batch->seq(), 7U);
  EXPECT_EQ(batch->stamp_ns(), 1'700'000'000'123'456'789);
  EXPECT_EQ(batch->session_frame(), pb::SESSION_FRAME_LOCAL);
  const pb::Rigid3& T = batch->t_frame_sensor();
  EXPECT_DOUBLE_EQ(T.translation().x(), 4.0);
  EXPECT_DOUBLE_EQ(T.translation().y(), -2.5);
  EXPECT_DOUBLE_EQ(T.translation().z(), 0.4);
  EXPECT_NEAR(T.rotation().w(), std::cos(0.15), 1e-12);
  EXPECT_NEAR(T.rotation().z(), std::sin(0.15), 1e-12);
  EXPECT_NEAR(T.rotation().x(), 0, 1e-12);
  EXPECT_NEAR(T.rotation().y(), 0, 1e-12);
  ASSERT_EQ(batch->lines_size(), 1);
  const pb::LineSegment& line = batch->lines(0);  // in the sensor frame: x = 2
  EXPECT_NEAR(line.a().x(), 2.0, 1e-9);
  EXPECT_NEAR(line.b().x(), 2.0, 1e-9);
  EXPECT_NEAR(std::abs(line.a().y() - line.b().y()), 4.0 * std::tan(M_PI / 18), 1e-9);
  EXPECT_EQ(line.a().z(), 0.0);
  EXPECT_EQ(line.b().z(), 0.0);
}

TEST(ObservationBatchTest, AScanWithNoLinesIsABatchWithNone) {
  LaserScan scan = WallScan();
  for (double& r : scan.ranges_m) r = std::numeric_limits<double>::infinity();
  const auto batch = ScanBatch(Header(), Pose(), scan, LineExtractionParams());
  ASSERT_TRUE(batch.ok());
  EXPECT_EQ(batch->lines_size(), 0);  // the pose still tells mapd where the robot looked
}

TEST(ObservationBatchTest, RefusesWhatTheServerWouldNamingTheField) {
  const auto refused = [](const BatchHeader& h, const Eigen::Isometry3d& T,
                          const std::vector<ExtractedLine>& lines, const std::string& field) {
    const auto batch = LineBatch(h, T, lines);
    ASSERT_FALSE(batch.ok()) << field;
    EXPECT_EQ(batch.status().code(), StatusCode::kInvalidArgument);
    EXPECT_NE(batch.status().message().find(field), std::string::npos)
        << batch.status().message() << " should name " << field;
  };
  BatchHeader h = Header();
  h.robot_id.clear();
  refused(h, Pose(), {}, "robot_id");
  h = Header();
  h.session_id.clear();
  refused(h, Pose(), {}, "session_id");
  h = Header();
  h.seq = 0;
  refused(h, Pose(), {}, "seq");
  Eigen::Isometry3d T = Pose();
  T.translation().x() = std::nan("");
  refused(Header(), T, {}, "T_frame_sensor");
  T = Pose();
  T.linear() *= 2;  // a scale is not a rotation
  refused(Header(), T, {}, "rotation");
  T = Pose();
  T.linear().col(0) *= -1;  // a mirror neither
  refused(Header(), T, {}, "rotation");
  ExtractedLine degenerate;
  degenerate.segment = {Vec2(1, 1), Vec2(1, 1)};
  refused(Header(), Pose(), {ExtractedLine{}, degenerate}, "lines[0]");
  ExtractedLine fine;
  fine.segment = {Vec2(0, 0), Vec2(1, 0)};
  refused(Header(), Pose(), {fine, degenerate}, "lines[1]");
  // And a bad scan: the extractor's message.
  LaserScan scan = WallScan();
  scan.ranges_m[2] = -1;
  const auto batch = ScanBatch(Header(), Pose(), scan, LineExtractionParams());
  ASSERT_FALSE(batch.ok());
  EXPECT_NE(batch.status().message().find("scan.ranges_m[2]"), std::string::npos);
}

TEST(ObservationBatchTest, CarriesPlanesAndNamesABadOne) {
  geometry::PlaneFeature floor;  // 1 m below the sensor
  floor.normal = Eigen::Vector3d::UnitZ();
  floor.offset = 1.0;
  floor.boundary = {{-1, -1, -1}, {1, -1, -1}, {1, 1, -1}, {-1, 1, -1}};
  const auto batch = FeatureBatch(Header(), Pose(), {}, {floor});
  ASSERT_TRUE(batch.ok()) << batch.status().message();
  ASSERT_EQ(batch->planes_size(), 1);
  EXPECT_EQ(batch->planes(0).normal().z(), 1.0);
  EXPECT_EQ(batch->planes(0).offset(), 1.0);
  EXPECT_EQ(batch->planes(0).boundary_size(), 4);
  EXPECT_EQ(batch->planes(0).boundary(2).x(), 1.0);

  geometry::PlaneFeature bad = floor;
  bad.normal *= 2;
  auto refused = FeatureBatch(Header(), Pose(), {}, {floor, bad});
  ASSERT_FALSE(refused.ok());
  EXPECT_NE(refused.status().message().find("planes[1].normal"), std::string::npos);
  bad = floor;
  bad.boundary.resize(2);
  refused = FeatureBatch(Header(), Pose(), {}, {bad});
  ASSERT_FALSE(refused.ok());
  EXPECT_NE(refused.status().message().find("planes[0].boundary has 2 points"), std::string::npos);
  bad = floor;
  bad.boundary[1].y() = std::nan("");
  refused = FeatureBatch(Header(), Pose(), {}, {bad});
  ASSERT_FALSE(refused.ok());
  EXPECT_NE(refused.status().message().find("planes[0].boundary[1]"), std::string::npos);
}

}  // namespace
}  // namespace mapd::robot
