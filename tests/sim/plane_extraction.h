// Planes from one simulated LiDAR scan: the robot library's extractor
// (client/robot/cloud_planes.h) on the scan's range image (one row per beam,
// columns wrapping around), plus what only a simulation knows: the world
// label most of each plane's points hit, for scoring against the truth.
#ifndef MAPD_TESTS_SIM_PLANE_EXTRACTION_H_
#define MAPD_TESTS_SIM_PLANE_EXTRACTION_H_

#include <cstddef>
#include <vector>

#include "client/robot/cloud_planes.h"
#include "common/status.h"
#include "geometry/observation.h"
#include "sim/lidar_sim.h"

namespace mapd::sim {

using PlaneExtractionParams = robot::PlaneExtractionParams;
using ExtractionStats = robot::PlaneExtractionStats;

struct ExtractedPlane {
  geometry::PlaneFeature feature;  // normal points towards the sensor
  size_t inliers = 0;
  int label = -2;  // the most common world label among the inliers
  double rms_m = 0.0;
};

// InvalidArgument for bad settings or a scan that is not beams x columns points.
StatusOr<std::vector<ExtractedPlane>> ExtractPlanes(const LidarScan& scan,
                                                    const PlaneExtractionParams& params,
                                                    ExtractionStats* stats = nullptr);

}  // namespace mapd::sim

#endif  // MAPD_TESTS_SIM_PLANE_EXTRACTION_H_
