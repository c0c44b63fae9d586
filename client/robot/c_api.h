/* The robot library's point-cloud side behind a C interface, for languages
 * with a C FFI: Python's ctypes (mapd_client.planes), and robot stacks that
 * cannot link C++. Library libmapd_robot_c.so (built with the plane
 * extractor, MAPD_WITH_ROBOT_PLANES). Every function that can fail returns 0,
 * or a mapd StatusCode (1: invalid argument, 2: not found, 8: internal) with
 * the reason in
 * `error` (NUL-terminated, cut to error_size). Nothing here throws or aborts
 * on bad input. Units: metres, degrees where named. */
#ifndef MAPD_CLIENT_ROBOT_C_API_H_
#define MAPD_CLIENT_ROBOT_C_API_H_

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/* robot::PlaneExtractionParams, field for field (cloud_planes.h).
 * segmentation: 0 RANSAC, 1 region growing. */
typedef struct mapd_plane_params {
  int segmentation;
  double distance_m;
  int max_iterations;
  uint64_t min_inliers;
  double min_extent_m;
  double min_width_m;
  int min_rows;
  double max_rms_m;
  int max_planes;
  double jump_base_m;
  double jump_factor;
  int normal_neighbours;
  double smoothness_deg;
  double max_curvature;
} mapd_plane_params;

/* The C++ defaults. */
void mapd_plane_params_default(mapd_plane_params* params);

typedef struct mapd_planes mapd_planes;

/* The planes of `count` points (x y z floats, sensor frame; NaN: no return).
 * rows x columns == count for an organised scan (wrap_columns for a 360
 * degree LiDAR); rows = columns = 0 for an unorganised cloud. params NULL:
 * the defaults. On success *out holds the planes (free with mapd_planes_free). */
int mapd_extract_planes(const float* xyz, size_t count, int rows, int columns, int wrap_columns,
                        const mapd_plane_params* params, mapd_planes** out, char* error,
                        size_t error_size);
size_t mapd_planes_count(const mapd_planes* planes);
/* Plane i (an i out of range leaves the outputs as they are): unit normal
 * towards the sensor, offset (n.x + offset = 0), refit
 * RMS, and the sizes of its boundary and of its inliers. */
void mapd_planes_get(const mapd_planes* planes, size_t i, double normal[3], double* offset_m,
                     double* rms_m, size_t* boundary_size, size_t* inlier_count);
/* Its boundary (3 * boundary_size doubles) and inliers (indices into xyz). */
void mapd_planes_boundary(const mapd_planes* planes, size_t i, double* xyz);
void mapd_planes_inliers(const mapd_planes* planes, size_t i, int32_t* indices);
void mapd_planes_free(mapd_planes* planes);

typedef struct mapd_cloud mapd_cloud;

/* A point cloud file (cloud_files.h: .pcd, .ply, .bin, .xyz, .txt, .dat). */
int mapd_read_cloud(const char* path, mapd_cloud** out, char* error, size_t error_size);
size_t mapd_cloud_size(const mapd_cloud* cloud);
/* rows > 1: organised, rows x columns; else 0 x 0. */
void mapd_cloud_shape(const mapd_cloud* cloud, int* rows, int* columns);
/* 3 * size floats, owned by the cloud. */
const float* mapd_cloud_points(const mapd_cloud* cloud);
void mapd_cloud_free(mapd_cloud* cloud);

#ifdef __cplusplus
}
#endif

#endif /* MAPD_CLIENT_ROBOT_C_API_H_ */
