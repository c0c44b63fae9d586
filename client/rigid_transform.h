// A rigid transform for the client, built from the API's Rigid3 (translation
// in metres, Hamilton unit quaternion): p_target = R p_source + t. Eigen does
// the quaternion maths; this adds the client's tolerant construction and the
// Euler angles its tables print.
#ifndef MAPD_CLIENT_RIGID_TRANSFORM_H_
#define MAPD_CLIENT_RIGID_TRANSFORM_H_

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>

namespace mapd::client {

struct Point3 {
  double x = 0, y = 0, z = 0;  // metres
};

struct RigidTransform {
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
  Point3 t;  // metres

  // From a quaternion (w, x, y, z), normalised here; a zero or non-finite
  // quaternion gives the identity rotation (the server refuses those, so this
  // only guards against a malformed file or answer).
  static RigidTransform FromQuaternion(double w, double x, double y, double z, Point3 translation) {
    RigidTransform T;
    T.t = translation;
    const Eigen::Quaterniond q(w, x, y, z);
    const double n = q.norm();
    if (n > 0 && std::isfinite(n)) T.R = q.normalized().toRotationMatrix();
    return T;
  }

  Point3 Apply(const Point3& p) const {
    const Eigen::Vector3d v = R * Eigen::Vector3d(p.x, p.y, p.z);
    return {v.x() + t.x, v.y() + t.y, v.z() + t.z};
  }

  // Z-Y-X Euler angles in degrees: R = Rz(yaw) Ry(pitch) Rx(roll), yaw and
  // roll in (-180, 180], pitch in [-90, 90] (Eigen's eulerAngles() would put
  // yaw in [0, 180] instead, which reads badly in a table).
  void YawPitchRollDeg(double* yaw, double* pitch, double* roll) const {
    constexpr double kDeg = 180.0 / M_PI;
    *yaw = std::atan2(R(1, 0), R(0, 0)) * kDeg;
    *pitch = std::asin(std::clamp(-R(2, 0), -1.0, 1.0)) * kDeg;
    *roll = std::atan2(R(2, 1), R(2, 2)) * kDeg;
  }
};

}  // namespace mapd::client

#endif  // MAPD_CLIENT_RIGID_TRANSFORM_H_
