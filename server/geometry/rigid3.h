// Rigid transforms in 3D. Naming follows T_target_source: T_map_sensor maps a
// point given in the sensor frame into the map frame. Translations in metres.
#ifndef MAPD_GEOMETRY_RIGID3_H_
#define MAPD_GEOMETRY_RIGID3_H_

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>

namespace mapd::geometry {

struct Rigid3 {
  Eigen::Quaterniond rotation = Eigen::Quaterniond::Identity();  // unit quaternion
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();         // metres

  static Rigid3 Identity() { return {}; }
  // From a quaternion (w, x, y, z) as the API and files carry it, normalised
  // here; a zero or non-finite quaternion gives the identity rotation (the
  // server refuses those: this only guards a reader of a malformed file or
  // answer).
  static Rigid3 FromQuaternion(double w, double x, double y, double z,
                               const Eigen::Vector3d& translation) {
    Rigid3 T;
    T.translation = translation;
    const Eigen::Quaterniond q(w, x, y, z);
    const double n = q.norm();
    if (n > 0 && std::isfinite(n)) T.rotation = q.normalized();
    return T;
  }

  Eigen::Vector3d operator*(const Eigen::Vector3d& p) const { return rotation * p + translation; }
  // Composition: (T_a_b * T_b_c) = T_a_c.
  Rigid3 operator*(const Rigid3& rhs) const {
    return {rotation * rhs.rotation, rotation * rhs.translation + translation};
  }
  Rigid3 inverse() const {
    const Eigen::Quaterniond inv = rotation.conjugate();
    return {inv, -(inv * translation)};
  }
  // Z-Y-X Euler angles in degrees, as tables print them: R = Rz(yaw)
  // Ry(pitch) Rx(roll), yaw and roll in (-180, 180], pitch in [-90, 90]
  // (Eigen's eulerAngles() puts yaw in [0, 180] instead, which reads badly).
  void YawPitchRollDeg(double* yaw, double* pitch, double* roll) const {
    constexpr double kDeg = 180.0 / M_PI;
    const Eigen::Matrix3d R = rotation.toRotationMatrix();
    *yaw = std::atan2(R(1, 0), R(0, 0)) * kDeg;
    *pitch = std::asin(std::clamp(-R(2, 0), -1.0, 1.0)) * kDeg;
    *roll = std::atan2(R(2, 1), R(2, 2)) * kDeg;
  }
  Eigen::Isometry3d ToIsometry() const {
    Eigen::Isometry3d iso = Eigen::Isometry3d::Identity();
    iso.linear() = rotation.toRotationMatrix();
    iso.translation() = translation;
    return iso;
  }
};

}  // namespace mapd::geometry

#endif  // MAPD_GEOMETRY_RIGID3_H_
