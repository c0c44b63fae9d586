// A rigid transform for the client (no Eigen needed): p_target = R p_source + t,
// built from the API's Rigid3 (translation in metres, Hamilton unit quaternion).
#ifndef MAPD_CLIENT_RIGID_TRANSFORM_H_
#define MAPD_CLIENT_RIGID_TRANSFORM_H_

#include <cmath>

namespace mapd::client {

struct Point3 {
  double x = 0, y = 0, z = 0;  // metres
};

struct RigidTransform {
  double R[3][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  Point3 t;  // metres

  // From a quaternion (w, x, y, z), normalised here; a zero quaternion gives the identity rotation.
  static RigidTransform FromQuaternion(double w, double x, double y, double z, Point3 translation) {
    RigidTransform T;
    T.t = translation;
    const double n = std::sqrt(w * w + x * x + y * y + z * z);
    if (!(n > 0) || !std::isfinite(n)) return T;
    w /= n, x /= n, y /= n, z /= n;
    T.R[0][0] = 1 - 2 * (y * y + z * z);
    T.R[0][1] = 2 * (x * y - w * z);
    T.R[0][2] = 2 * (x * z + w * y);
    T.R[1][0] = 2 * (x * y + w * z);
    T.R[1][1] = 1 - 2 * (x * x + z * z);
    T.R[1][2] = 2 * (y * z - w * x);
    T.R[2][0] = 2 * (x * z - w * y);
    T.R[2][1] = 2 * (y * z + w * x);
    T.R[2][2] = 1 - 2 * (x * x + y * y);
    return T;
  }

  Point3 Apply(const Point3& p) const {
    return {R[0][0] * p.x + R[0][1] * p.y + R[0][2] * p.z + t.x,
            R[1][0] * p.x + R[1][1] * p.y + R[1][2] * p.z + t.y,
            R[2][0] * p.x + R[2][1] * p.y + R[2][2] * p.z + t.z};
  }

  // Z-Y-X Euler angles in degrees: R = Rz(yaw) Ry(pitch) Rx(roll).
  void YawPitchRollDeg(double* yaw, double* pitch, double* roll) const {
    constexpr double kDeg = 180.0 / M_PI;
    *yaw = std::atan2(R[1][0], R[0][0]) * kDeg;
    *pitch = std::asin(std::fmax(-1.0, std::fmin(1.0, -R[2][0]))) * kDeg;
    *roll = std::atan2(R[2][1], R[2][2]) * kDeg;
  }
};

}  // namespace mapd::client

#endif  // MAPD_CLIENT_RIGID_TRANSFORM_H_
