// CARMEN laser logs: FLASER's 180 degree fan, ROBOTLASER1's own laser
// geometry (preferred when a log has both), gzip read like plain text, and a
// malformed line named by file and line number.
#include "client/robot/carmen_log.h"

#include <gtest/gtest.h>
#include <zlib.h>

#include <cmath>
#include <fstream>
#include <string>

#include "common/temp_dir.h"

namespace mapd::robot {
namespace {

constexpr char kFlaser[] = "FLASER 4 1.0 2.0 3.0 4.0 5.5 -2.0 0.25 9 9 9 1200.5 host 1200.6\n";
// A 270 degree laser, 0.5 m .. 30 m: 3 beams, 2 remissions, laser pose 1 2 0.5.
constexpr char kRobotLaser[] =
    "ROBOTLASER1 4 -2.356 4.712 0.01 30.0 0.01 0 3 1.5 30.0 2.5 2 0.1 0.2 "
    "1.0 2.0 0.5 0.9 1.9 0.5 0.1 0.0 0.55 0.35 0.0 1300.25 host 1300.3\n";

TEST(CarmenLogTest, FlaserIsTheHalfCircleFan) {
  testing::TempDir dir;
  const auto scans =
      ReadCarmenLaserLog(dir.Write("a.log", "# comment\nODOM 1 2 3\n" + std::string(kFlaser)));
  ASSERT_TRUE(scans.ok()) << scans.status().message();
  ASSERT_EQ(scans->size(), 1u);
  const CarmenScan& s = scans->front();
  EXPECT_EQ(s.ranges_m, (std::vector<double>{1, 2, 3, 4}));
  EXPECT_DOUBLE_EQ(s.x_m, 5.5);
  EXPECT_DOUBLE_EQ(s.y_m, -2.0);
  EXPECT_DOUBLE_EQ(s.theta_rad, 0.25);
  EXPECT_DOUBLE_EQ(s.timestamp_s, 1200.5);
  const LaserScan laser = ToLaserScan(s, 80);
  EXPECT_DOUBLE_EQ(laser.angle_min_rad, -M_PI / 2);
  EXPECT_DOUBLE_EQ(laser.angle_increment_rad, M_PI / 4);
  EXPECT_DOUBLE_EQ(laser.range_max_m, 80);
}

TEST(CarmenLogTest, RobotLaserCarriesItsOwnLaserAndWinsOverFlaser) {
  testing::TempDir dir;
  const auto scans = ReadCarmenLaserLog(
      dir.Write("b.log", std::string(kFlaser) + kRobotLaser + kFlaser + kRobotLaser));
  ASSERT_TRUE(scans.ok()) << scans.status().message();
  ASSERT_EQ(scans->size(), 2u);  // the ROBOTLASER1 lines only
  const CarmenScan& s = scans->front();
  EXPECT_EQ(s.ranges_m, (std::vector<double>{1.5, 30.0, 2.5}));
  EXPECT_DOUBLE_EQ(s.x_m, 1.0);
  EXPECT_DOUBLE_EQ(s.y_m, 2.0);
  EXPECT_DOUBLE_EQ(s.theta_rad, 0.5);
  EXPECT_DOUBLE_EQ(s.timestamp_s, 1300.25);
  const LaserScan laser = ToLaserScan(s, 80);
  EXPECT_DOUBLE_EQ(laser.angle_min_rad, -2.356);
  EXPECT_DOUBLE_EQ(laser.angle_increment_rad, 0.01);
  EXPECT_DOUBLE_EQ(laser.range_max_m, 30.0);  // the laser's own maximum, below the flag's
  EXPECT_DOUBLE_EQ(ToLaserScan(s, 20).range_max_m, 20.0);
}

TEST(CarmenLogTest, GzipIsReadLikePlainText) {
  testing::TempDir dir;
  const std::string path = dir.File("c.log.gz");
  gzFile f = gzopen(path.c_str(), "wb");
  ASSERT_NE(f, nullptr);
  gzputs(f, kRobotLaser);
  gzclose(f);
  const auto scans = ReadCarmenLaserLog(path);
  ASSERT_TRUE(scans.ok()) << scans.status().message();
  EXPECT_EQ(scans->size(), 1u);
}

TEST(CarmenLogTest, AMalformedLineIsNamedAndAMissingFileIsNotFound) {
  testing::TempDir dir;
  const auto expect_bad = [&](const std::string& text, const std::string& what) {
    const std::string path = dir.Write("bad.log", "PARAM x 1\n" + text);
    const auto scans = ReadCarmenLaserLog(path);
    ASSERT_FALSE(scans.ok()) << text;
    EXPECT_EQ(scans.status().code(), StatusCode::kInvalidArgument);
    EXPECT_NE(scans.status().message().find(path + ":2: " + what), std::string::npos)
        << scans.status().message();
  };
  expect_bad("FLASER x\n", "FLASER without a beam count");
  expect_bad("FLASER 3 1 2\n", "missing range");
  expect_bad("FLASER 2 1 2 0 0\n", "missing pose or timestamp");
  expect_bad("ROBOTLASER1 4 -2 4 0.01\n", "ROBOTLASER1 without its laser settings");
  expect_bad("ROBOTLASER1 4 -2 4 0 30 0.01 0 1 1\n", "ROBOTLASER1 needs a finite start angle");
  expect_bad("ROBOTLASER1 4 -2 4 0.01 30 0.01 0 2 1\n", "missing range");
  expect_bad("ROBOTLASER1 4 -2 4 0.01 30 0.01 0 1 1 3 0.1\n", "missing remissions");
  expect_bad("ROBOTLASER1 4 -2 4 0.01 30 0.01 0 1 1 0 1 2 3\n", "missing pose or timestamp");
  const auto missing = ReadCarmenLaserLog(dir.File("none.log"));
  EXPECT_EQ(missing.status().code(), StatusCode::kNotFound);
}

}  // namespace
}  // namespace mapd::robot
