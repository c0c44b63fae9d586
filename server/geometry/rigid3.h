// Rigid transforms in 3D. Naming follows T_target_source: T_map_sensor maps a
// point given in the sensor frame into the map frame. Translations in metres.
#ifndef MAPD_GEOMETRY_RIGID3_H_
#define MAPD_GEOMETRY_RIGID3_H_

#include <Eigen/Geometry>

namespace mapd::geometry {

struct Rigid3 {
  Eigen::Quaterniond rotation = Eigen::Quaterniond::Identity();  // unit quaternion
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();         // metres

  static Rigid3 Identity() { return {}; }

  Eigen::Vector3d operator*(const Eigen::Vector3d& p) const { return rotation * p + translation; }
  // Composition: (T_a_b * T_b_c) = T_a_c.
  Rigid3 operator*(const Rigid3& rhs) const {
    return {rotation * rhs.rotation, rotation * rhs.translation + translation};
  }
  Rigid3 inverse() const {
    const Eigen::Quaterniond inv = rotation.conjugate();
    return {inv, -(inv * translation)};
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
