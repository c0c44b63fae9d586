// Planes from one organised LiDAR scan (issue 10): iterative RANSAC
// (pcl::SACSegmentation, SACMODEL_PLANE) takes the largest plane of the
// points left; its inliers are split into components connected in the scan's
// range image (beam/column neighbours), so two coplanar facades with a street
// between them stay apart; each component that is large enough in points,
// extent and rows is refitted by least squares (PCA) and becomes a
// geometry::PlaneFeature in the sensor frame, boundary = convex hull of its
// inliers projected into the plane. All inliers of a RANSAC plane leave the
// pool, kept or not. Deterministic: PCL's RANSAC uses a fixed seed.
#ifndef MAPD_TESTS_SIM_PLANE_EXTRACTION_H_
#define MAPD_TESTS_SIM_PLANE_EXTRACTION_H_

#include <cstddef>
#include <vector>

#include "common/status.h"
#include "geometry/observation.h"
#include "sim/lidar_sim.h"

namespace mapd::sim {

struct PlaneExtractionParams {
  double distance_m = 0.06;   // RANSAC inlier threshold
  int max_iterations = 300;   // RANSAC iterations per plane
  size_t min_inliers = 120;   // per kept component (and to keep looking)
  double min_extent_m = 1.0;  // longest in-plane side of the component
  double min_width_m = 0.3;   // shortest in-plane side (a single scan line has none)
  int min_beams = 3;          // distinct beams (rows) in a component
  double max_rms_m = 0.05;    // least-squares residual of the refit
  int max_planes = 24;        // RANSAC rounds per scan
  // Neighbours on one beam are connected if closer than base + factor * range.
  double jump_base_m = 0.3;
  double jump_factor = 0.03;
  Status Validate() const;
};

struct ExtractedPlane {
  geometry::PlaneFeature feature;  // normal points towards the sensor
  size_t inliers = 0;
  int label = -2;  // the most common world label among the inliers
  double rms_m = 0.0;
};

struct ExtractionStats {
  size_t ransac_rounds = 0;
  // Components of min_inliers points or more that failed a gate, by gate.
  size_t rejected_beams = 0;  // fewer than min_beams rows
  size_t rejected_rough = 0;  // refit RMS above max_rms_m
  size_t rejected_small = 0;  // extent or width below the minimum
};

// REQUIRES: params.Validate().ok(); InvalidArgument for a malformed scan.
StatusOr<std::vector<ExtractedPlane>> ExtractPlanes(const LidarScan& scan,
                                                    const PlaneExtractionParams& params,
                                                    ExtractionStats* stats = nullptr);

}  // namespace mapd::sim

#endif  // MAPD_TESTS_SIM_PLANE_EXTRACTION_H_
