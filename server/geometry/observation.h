// What a robot reports in one observation batch, in its sensor frame.
//
// These plain types are shared by the service (which converts protobuf into
// them), storage (which persists them verbatim: raw observations are never
// discarded) and fusion (which consumes their ground-plane projections).
#ifndef MAPD_GEOMETRY_OBSERVATION_H_
#define MAPD_GEOMETRY_OBSERVATION_H_

#include <Eigen/Core>
#include <vector>

#include "geometry/rigid3.h"

namespace mapd::geometry {

// A line segment with 3D endpoints in the sensor frame (metres). 2D sensors set z = 0.
struct LineFeature3 {
  Eigen::Vector3d a = Eigen::Vector3d::Zero();
  Eigen::Vector3d b = Eigen::Vector3d::Zero();
};

// A planar patch in the sensor frame: points x with normal.dot(x) + offset = 0,
// bounded by `boundary` (>= 3 points on or near the plane, metres).
struct PlaneFeature {
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();  // unit length
  double offset = 0.0;                                // metres
  std::vector<Eigen::Vector3d> boundary;
};

// One batch of features seen from one sensor pose.
struct SensorObservation {
  Rigid3 T_frame_sensor;  // sensor pose in the robot session's frame
  std::vector<LineFeature3> lines;
  std::vector<PlaneFeature> planes;
};

}  // namespace mapd::geometry

#endif  // MAPD_GEOMETRY_OBSERVATION_H_
