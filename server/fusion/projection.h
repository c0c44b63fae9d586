// From a robot's observation (sensor frame) to ground-plane features in the
// map frame (docs/algorithms.md A.1, Eq. 1-4).
#ifndef MAPD_FUSION_PROJECTION_H_
#define MAPD_FUSION_PROJECTION_H_

#include <vector>

#include "common/status.h"
#include "fusion/engine.h"
#include "fusion/params.h"
#include "geometry/observation.h"
#include "geometry/rigid3.h"

namespace mapd::fusion {

// A plane that is not near-vertical (floor, ceiling, ramp): kept apart, in the map frame.
struct MapPlane {
  FeatureId id = 0;
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();
  double offset_m = 0.0;
  std::vector<Eigen::Vector3d> boundary;
};

struct ProjectedObservation {
  std::vector<GroundFeature> ground;   // lines, and near-vertical planes as segments
  std::vector<MapPlane> other_planes;  // planes tilted more than max_plane_tilt_rad
  size_t skipped = 0;  // features whose ground projection degenerates (a vertical line)
  // The sensor's origin in the map frame, on the ground plane: where the rays
  // to every feature started (free-space evidence, FusionEngine::AddFrom).
  geometry::Vec2 sensor_xy_m = geometry::Vec2::Zero();
};

// Transforms every feature of `obs` by T_map_sensor = T_map_frame * obs.T_frame_sensor
// and projects it onto the ground plane. Feature ids are first_id, first_id+1, ...
// in the order lines then planes. A 3D line keeps its z range; a vertical plane
// becomes the segment spanned by the extreme projections of its boundary points.
// A feature whose ground projection is shorter than 1 mm (a vertical line, a
// vertical plane whose boundary projects to one point) is left out and counted
// in `skipped`: it is kept raw in storage but has nothing to fuse. Non-finite
// input is refused with InvalidArgument naming the feature, e.g. "lines[3]".
StatusOr<ProjectedObservation> ProjectToGround(const geometry::SensorObservation& obs,
                                               const geometry::Rigid3& T_map_frame,
                                               FeatureId first_id, const FusionParams& params);

}  // namespace mapd::fusion

#endif  // MAPD_FUSION_PROJECTION_H_
