// A rigid transform as seven float8 parameters or columns (qw, qx, qy, qz,
// tx, ty, tz), the layout of every pose the PostgreSQL schema stores.
// Internal to the PostgreSQL backend.
#ifndef MAPD_STORAGE_POSTGRES_POSE_PARAMS_H_
#define MAPD_STORAGE_POSTGRES_POSE_PARAMS_H_

#include <Eigen/Geometry>

#include "geometry/rigid3.h"
#include "storage/postgres/pq.h"

namespace mapd::storage {

inline void AddPose(PgParams& p, const geometry::Rigid3& T) {
  p.Double(T.rotation.w()).Double(T.rotation.x()).Double(T.rotation.y()).Double(T.rotation.z());
  p.Double(T.translation.x()).Double(T.translation.y()).Double(T.translation.z());
}

inline geometry::Rigid3 PoseAt(const PgResult& r, int row, int first) {
  geometry::Rigid3 T;
  T.rotation = Eigen::Quaterniond(r.Double(row, first), r.Double(row, first + 1),
                                  r.Double(row, first + 2), r.Double(row, first + 3));
  T.translation = {r.Double(row, first + 4), r.Double(row, first + 5), r.Double(row, first + 6)};
  return T;
}

}  // namespace mapd::storage

#endif  // MAPD_STORAGE_POSTGRES_POSE_PARAMS_H_
