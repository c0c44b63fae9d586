#include "client/robot/pose_files.h"

#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <fstream>

namespace mapd::robot {
namespace {

// The numbers of one line; false if something else is on it.
bool Numbers(const std::string& line, std::vector<double>* out) {
  out->clear();
  const char* cursor = line.c_str();
  for (;;) {
    while (*cursor == ' ' || *cursor == '\t' || *cursor == '\r' || *cursor == ',') ++cursor;
    if (*cursor == '\0') return true;
    char* end = nullptr;
    errno = 0;
    const double v = std::strtod(cursor, &end);
    if (end == cursor || errno == ERANGE) return false;
    out->push_back(v);
    cursor = end;
  }
}

bool Skip(const std::string& line) {
  const size_t first = line.find_first_not_of(" \t\r");
  return first == std::string::npos || line[first] == '#';
}

Status Bad(const std::string& where, const std::string& what) {
  return Status::InvalidArgument(where + ": " + what);
}

Status ParseTum(const std::vector<double>& v, const std::string& where, StampedPose* pose) {
  if (v.size() != 8) {
    return Bad(where, "a TUM pose is 8 numbers (timestamp tx ty tz qx qy qz qw), got " +
                          std::to_string(v.size()));
  }
  Eigen::Quaterniond q(v[7], v[4], v[5], v[6]);
  if (std::abs(q.norm() - 1.0) > 0.01) {
    return Bad(where,
               "quaternion (qx qy qz qw) is not of unit length (" + std::to_string(q.norm()) + ")");
  }
  pose->stamp_s = v[0];
  pose->T_world_sensor.linear() = q.normalized().toRotationMatrix();
  pose->T_world_sensor.translation() = Eigen::Vector3d(v[1], v[2], v[3]);
  return Status::Ok();
}

// A 3 x 4 [R | t] row-major, as KITTI writes poses and calibrations.
Status ParseMatrix(const double* v, const std::string& where, Eigen::Isometry3d* T) {
  Eigen::Matrix3d R;
  R << v[0], v[1], v[2], v[4], v[5], v[6], v[8], v[9], v[10];
  if ((R.transpose() * R - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff() > 1e-3 ||
      R.determinant() < 0) {
    return Bad(where, "the 3 x 3 part is not a rotation");
  }
  // Re-orthonormalise the 6-digit text's rounding away.
  T->linear() = Eigen::Quaterniond(R).normalized().toRotationMatrix();
  T->translation() = Eigen::Vector3d(v[3], v[7], v[11]);
  return Status::Ok();
}

}  // namespace

StatusOr<std::vector<StampedPose>> ReadPoseFile(const std::string& path, PoseFormat format,
                                                PoseFormat* detected) {
  std::ifstream in(path);
  if (!in) return Status::NotFound("cannot open pose file " + path);
  std::vector<StampedPose> poses;
  std::string line;
  std::vector<double> v;
  size_t number = 0;
  while (std::getline(in, line)) {
    ++number;
    if (Skip(line)) continue;
    const std::string where = path + ":" + std::to_string(number);
    if (!Numbers(line, &v)) return Bad(where, "not a line of numbers");
    for (double x : v) {
      if (!std::isfinite(x)) return Bad(where, "a value is not finite");
    }
    if (format == PoseFormat::kAuto) {
      if (v.size() == 8) {
        format = PoseFormat::kTum;
      } else if (v.size() == 12) {
        format = PoseFormat::kKitti;
      } else {
        return Bad(where, "neither a TUM pose (8 numbers) nor a KITTI pose (12): " +
                              std::to_string(v.size()) + " numbers");
      }
    }
    StampedPose pose;
    if (format == PoseFormat::kTum) {
      MAPD_RETURN_IF_ERROR(ParseTum(v, where, &pose));
    } else {
      if (v.size() != 12) {
        return Bad(where,
                   "a KITTI pose is 12 numbers (a 3 x 4 matrix), got " + std::to_string(v.size()));
      }
      MAPD_RETURN_IF_ERROR(ParseMatrix(v.data(), where, &pose.T_world_sensor));
    }
    poses.push_back(pose);
  }
  if (in.bad()) return Status::InvalidArgument("cannot read " + path);
  if (detected != nullptr) *detected = format;
  return poses;
}

StatusOr<std::vector<double>> ReadKittiTimes(const std::string& path) {
  std::ifstream in(path);
  if (!in) return Status::NotFound("cannot open " + path);
  std::vector<double> times, v;
  std::string line;
  size_t number = 0;
  while (std::getline(in, line)) {
    ++number;
    if (Skip(line)) continue;
    if (!Numbers(line, &v) || v.size() != 1 || !std::isfinite(v[0])) {
      return Bad(path + ":" + std::to_string(number), "not one time in seconds");
    }
    times.push_back(v[0]);
  }
  return times;
}

StatusOr<Eigen::Isometry3d> ReadKittiVelodyneToCamera(const std::string& calib_path) {
  std::ifstream in(calib_path);
  if (!in) return Status::NotFound("cannot open " + calib_path);
  std::string line;
  std::vector<double> v;
  size_t number = 0;
  while (std::getline(in, line)) {
    ++number;
    if (line.compare(0, 3, "Tr:") != 0) continue;
    const std::string where = calib_path + ":" + std::to_string(number);
    if (!Numbers(line.substr(3), &v) || v.size() != 12) return Bad(where, "Tr: is not 12 numbers");
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    MAPD_RETURN_IF_ERROR(ParseMatrix(v.data(), where, &T));
    return T;
  }
  return Status::InvalidArgument(calib_path + " has no 'Tr:' line");
}

}  // namespace mapd::robot
