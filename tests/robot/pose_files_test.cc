// Trajectory files of 3D scan folders: TUM (time, position, quaternion) and
// KITTI (3 x 4 matrices) told apart by their count of numbers, KITTI's times
// and calibration, and every malformed line named by file and number.
#include "client/robot/pose_files.h"

#include <gtest/gtest.h>

#include <fstream>
#include <string>

#include "common/temp_dir.h"

namespace mapd::robot {
namespace {

TEST(PoseFilesTest, TumAndKittiAreToldApart) {
  testing::TempDir dir;
  PoseFormat detected = PoseFormat::kAuto;
  // A quarter turn about z (qz = qw = sqrt(1/2)), written to 6 digits.
  const auto tum = ReadPoseFile(
      dir.Write("tum.txt",
                "# timestamp tx ty tz qx qy qz qw\n\n1305031102.5 1 2 3 0 0 0.707107 0.707107\n"),
      PoseFormat::kAuto, &detected);
  ASSERT_TRUE(tum.ok()) << tum.status().message();
  EXPECT_EQ(detected, PoseFormat::kTum);
  ASSERT_EQ(tum->size(), 1u);
  EXPECT_DOUBLE_EQ(tum->front().stamp_s, 1305031102.5);
  EXPECT_TRUE(tum->front().T_world_sensor.translation().isApprox(Eigen::Vector3d(1, 2, 3)));
  EXPECT_TRUE((tum->front().T_world_sensor.linear() * Eigen::Vector3d::UnitX())
                  .isApprox(Eigen::Vector3d::UnitY(), 1e-6));

  const auto kitti =
      ReadPoseFile(dir.Write("00.txt", "1 0 0 0.5 0 1 0 -0.25 0 0 1 7\n0 -1 0 1 1 0 0 2 0 0 1 3\n"),
                   PoseFormat::kAuto, &detected);
  ASSERT_TRUE(kitti.ok()) << kitti.status().message();
  EXPECT_EQ(detected, PoseFormat::kKitti);
  ASSERT_EQ(kitti->size(), 2u);
  EXPECT_TRUE(kitti->front().T_world_sensor.translation().isApprox(Eigen::Vector3d(0.5, -0.25, 7)));
  EXPECT_TRUE((kitti->back().T_world_sensor.linear() * Eigen::Vector3d::UnitX())
                  .isApprox(Eigen::Vector3d::UnitY()));

  const auto times = ReadKittiTimes(dir.Write("times.txt", "0.000000e+00\n1.036e-01\n"));
  ASSERT_TRUE(times.ok());
  EXPECT_EQ(*times, (std::vector<double>{0.0, 0.1036}));
  const auto tr = ReadKittiVelodyneToCamera(dir.Write(
      "calib.txt", "P0: 1 2 3 4 5 6 7 8 9 10 11 12\nTr: 0 -1 0 0 0 0 -1 -0.08 1 0 0 -0.27\n"));
  ASSERT_TRUE(tr.ok()) << tr.status().message();
  EXPECT_TRUE(tr->translation().isApprox(Eigen::Vector3d(0, -0.08, -0.27)));
  EXPECT_TRUE((tr->linear() * Eigen::Vector3d::UnitX()).isApprox(Eigen::Vector3d::UnitZ()));
}

TEST(PoseFilesTest, AMalformedLineIsNamed) {
  testing::TempDir dir;
  const auto expect_bad = [&](const std::string& text, PoseFormat format, const std::string& what) {
    const std::string path = dir.Write("bad.txt", "# header\n" + text);
    const auto poses = ReadPoseFile(path, format);
    ASSERT_FALSE(poses.ok()) << text;
    EXPECT_EQ(poses.status().code(), StatusCode::kInvalidArgument);
    EXPECT_NE(poses.status().message().find(path + ":2: " + what), std::string::npos)
        << poses.status().message();
  };
  expect_bad("1 2 3\n", PoseFormat::kAuto, "neither a TUM pose (8 numbers) nor a KITTI pose (12)");
  expect_bad("1 2 3 4 5 6 7 x\n", PoseFormat::kAuto, "not a line of numbers");
  expect_bad("1 2 3 4 0 0 0 2\n", PoseFormat::kTum,
             "quaternion (qx qy qz qw) is not of unit length");
  expect_bad("1 2 3 4 0 0 0 nan\n", PoseFormat::kTum, "a value is not finite");
  expect_bad("1 0 0 0 0 1 0 0 0 0 1 0\n", PoseFormat::kTum, "a TUM pose is 8 numbers");
  expect_bad("1 2 3 4 0 0 0 1\n", PoseFormat::kKitti, "a KITTI pose is 12 numbers");
  expect_bad("2 0 0 0 0 1 0 0 0 0 1 0\n", PoseFormat::kKitti, "the 3 x 3 part is not a rotation");
  expect_bad("-1 0 0 0 0 1 0 0 0 0 1 0\n", PoseFormat::kKitti, "the 3 x 3 part is not a rotation");
  EXPECT_EQ(ReadPoseFile(dir.File("none.txt"), PoseFormat::kAuto).status().code(),
            StatusCode::kNotFound);
  EXPECT_FALSE(ReadKittiVelodyneToCamera(dir.Write("c.txt", "P0: 1 2\n")).ok());
  EXPECT_FALSE(ReadKittiTimes(dir.Write("t.txt", "0.1 0.2\n")).ok());
}

}  // namespace
}  // namespace mapd::robot
