// Plane observations from one 3D scan, as a robot makes them before it sends
// a batch: iterative RANSAC (pcl::SACSegmentation, SACMODEL_PLANE) takes the
// largest plane of the points left; its inliers are split into connected
// components, so two coplanar facades with a street between them stay apart.
// An organised scan (a spinning LiDAR's range image, a depth camera's) joins
// image neighbours (row and column, a jump limit along a row); an unorganised
// one (a filtered or merged cloud, a PLY's vertices) joins points closer than
// the jump limit in space (a k-d tree). Each
// component large enough in points, extent and rows is refitted by least
// squares (PCA) and becomes a plane in the sensor frame, its boundary the
// convex hull of its inliers projected into the plane, its normal towards the
// sensor. All inliers of a RANSAC plane leave the pool, kept or not.
// Deterministic: PCL's RANSAC uses a fixed seed. Measured on simulated and
// real scans: docs/planes-3d.md.
#ifndef MAPD_CLIENT_ROBOT_CLOUD_PLANES_H_
#define MAPD_CLIENT_ROBOT_CLOUD_PLANES_H_

#include <Eigen/Core>
#include <cstddef>
#include <vector>

#include "common/status.h"
#include "geometry/observation.h"

namespace mapd::robot {

// An organised scan: rows x columns points, row-major, in the sensor frame
// (metres); a non-finite point is no return. A spinning LiDAR: one row per
// beam, one column per azimuth step (its columns wrap around: wrap_columns).
struct OrganisedCloud {
  int rows = 0;
  int columns = 0;
  std::vector<Eigen::Vector3f> points;
  bool wrap_columns = false;  // the last column is next to the first (a 360 deg scan)
};

// How points are grouped into candidate planes. RANSAC measured better on
// simulated and real scans (docs/robot-library.md, "RANSAC or region
// growing"); region growing (pcl::RegionGrowing on k-nearest-neighbour
// normals, each region through the same gates) stays for comparison.
enum class PlaneSegmentation { kRansac, kRegionGrowing };

struct PlaneExtractionParams {
  PlaneSegmentation segmentation = PlaneSegmentation::kRansac;
  double distance_m = 0.06;   // RANSAC inlier threshold: (0, 1]
  int max_iterations = 300;   // RANSAC iterations per plane: >= 1
  size_t min_inliers = 120;   // per kept component (and to keep looking): >= 3
  double min_extent_m = 1.0;  // longest in-plane side of the component: >= 0
  double min_width_m = 0.3;   // shortest in-plane side (a single scan line has none): >= 0
  int min_rows = 3;           // distinct rows (beams) in a component (organised only): >= 1
  double max_rms_m = 0.05;    // least-squares residual of the refit: > 0
  int max_planes = 24;        // RANSAC rounds per scan: >= 1
  // Row neighbours (organised) or any two inliers (unorganised) are connected
  // if closer than base + factor * range.
  double jump_base_m = 0.3;
  double jump_factor = 0.03;
  // Region growing only: neighbours per normal and per step, the largest
  // angle between neighbouring normals (degrees) and the largest curvature
  // (PCL's surface variation, 0..1/3) a region grows through.
  int normal_neighbours = 20;   // [3, 200]
  double smoothness_deg = 5.0;  // (0, 90]
  double max_curvature = 0.05;  // (0, 1]
  Status Validate() const;      // InvalidArgument naming the field
};

struct ExtractedPlane {
  geometry::PlaneFeature feature;  // sensor frame; normal towards the sensor
  std::vector<int> indices;        // the component's points (into the cloud's points)
  double rms_m = 0.0;              // of the refit
};

// Why components of min_inliers points or more were not kept.
struct PlaneExtractionStats {
  size_t ransac_rounds = 0;
  size_t rejected_rows = 0;   // fewer than min_rows rows
  size_t rejected_rough = 0;  // refit RMS above max_rms_m
  size_t rejected_small = 0;  // extent or width below the minimum
};

// The planes of `cloud`. InvalidArgument for bad settings and for a cloud
// that is not rows x columns points (rows and columns >= 1). A cloud without
// planes (or without returns) gives an empty list.
StatusOr<std::vector<ExtractedPlane>> ExtractPlanes(const OrganisedCloud& cloud,
                                                    const PlaneExtractionParams& params,
                                                    PlaneExtractionStats* stats = nullptr);

// The planes of an unorganised cloud (sensor frame, metres; non-finite
// points ignored). InvalidArgument for bad settings. The same gates, but
// min_rows: an unorganised cloud has no rows.
StatusOr<std::vector<ExtractedPlane>> ExtractPlanes(const std::vector<Eigen::Vector3f>& points,
                                                    const PlaneExtractionParams& params,
                                                    PlaneExtractionStats* stats = nullptr);

}  // namespace mapd::robot

#endif  // MAPD_CLIENT_ROBOT_CLOUD_PLANES_H_
