// A rigid transform in seven REAL columns (qw, qx, qy, qz, tx, ty, tz), the
// layout of every pose the schema stores (sessions, observations, merge
// inputs, submap placements). Internal to the storage library.
#ifndef MAPD_STORAGE_SQLITE_POSE_COLUMNS_H_
#define MAPD_STORAGE_SQLITE_POSE_COLUMNS_H_

#include <Eigen/Geometry>

#include "geometry/rigid3.h"
#include "storage/sqlite/sqlite.h"

namespace mapd::storage {

inline void BindPose(Statement& s, int first, const geometry::Rigid3& T) {
  s.Bind(first, T.rotation.w())
      .Bind(first + 1, T.rotation.x())
      .Bind(first + 2, T.rotation.y())
      .Bind(first + 3, T.rotation.z())
      .Bind(first + 4, T.translation.x())
      .Bind(first + 5, T.translation.y())
      .Bind(first + 6, T.translation.z());
}

inline geometry::Rigid3 ColumnPose(const Statement& s, int first) {
  geometry::Rigid3 T;
  T.rotation = Eigen::Quaterniond(s.ColumnDouble(first), s.ColumnDouble(first + 1),
                                  s.ColumnDouble(first + 2), s.ColumnDouble(first + 3));
  T.translation = {s.ColumnDouble(first + 4), s.ColumnDouble(first + 5), s.ColumnDouble(first + 6)};
  return T;
}

}  // namespace mapd::storage

#endif  // MAPD_STORAGE_SQLITE_POSE_COLUMNS_H_
