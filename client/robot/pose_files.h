// Trajectory files that come with recorded 3D scans, for replaying them
// (mapctl replay): one sensor pose a scan, in the data set's world frame.
//
//   TUM:   timestamp tx ty tz qx qy qz qw      (seconds, metres, unit quaternion)
//   KITTI: r11 r12 r13 tx r21 r22 r23 ty r31 r32 r33 tz   (a 3 x 4 matrix a line, no time)
//
// Lines starting with # and blank lines are skipped.
#ifndef MAPD_CLIENT_ROBOT_POSE_FILES_H_
#define MAPD_CLIENT_ROBOT_POSE_FILES_H_

#include <Eigen/Geometry>
#include <string>
#include <vector>

#include "common/status.h"

namespace mapd::robot {

enum class PoseFormat { kAuto, kTum, kKitti };

struct StampedPose {
  double stamp_s = 0.0;  // TUM's; KITTI's from its times.txt, else 0
  Eigen::Isometry3d T_world_sensor = Eigen::Isometry3d::Identity();
};

// Every pose of `path` in file order. kAuto picks by the first line's count of
// numbers (8: TUM, 12: KITTI), and says which in *detected (if given). NotFound if it cannot be
// opened; InvalidArgument naming the line for a wrong count of numbers, a non-finite value, a
// quaternion far from unit length (renormalised when within 1 %) or a rotation that is not one
// (KITTI: |R^T R - I| > 1e-3).
StatusOr<std::vector<StampedPose>> ReadPoseFile(const std::string& path, PoseFormat format,
                                                PoseFormat* detected = nullptr);

// KITTI odometry extras: the numbers of times.txt (seconds, one a line) and
// the Tr (velodyne to left camera) of calib.txt.
StatusOr<std::vector<double>> ReadKittiTimes(const std::string& path);
StatusOr<Eigen::Isometry3d> ReadKittiVelodyneToCamera(const std::string& calib_path);

}  // namespace mapd::robot

#endif  // MAPD_CLIENT_ROBOT_POSE_FILES_H_
