#include "client/robot/c_api.h"

#include <algorithm>
#include <cstring>
#include <exception>
#include <string>
#include <vector>

#include "client/robot/cloud_files.h"
#include "client/robot/cloud_planes.h"

struct mapd_planes {
  std::vector<mapd::robot::ExtractedPlane> planes;
};

struct mapd_cloud {
  mapd::robot::CloudFile file;
};

namespace {

int Fail(const mapd::Status& status, char* error, size_t error_size) {
  if (error != nullptr && error_size > 0) {
    const std::string& m = status.message();
    const size_t n = std::min(m.size(), error_size - 1);
    std::memcpy(error, m.data(), n);
    error[n] = '\0';
  }
  return static_cast<int>(status.code());
}

mapd::robot::PlaneExtractionParams FromC(const mapd_plane_params& c) {
  mapd::robot::PlaneExtractionParams p;
  p.segmentation = c.segmentation == 1 ? mapd::robot::PlaneSegmentation::kRegionGrowing
                                       : mapd::robot::PlaneSegmentation::kRansac;
  p.distance_m = c.distance_m;
  p.max_iterations = c.max_iterations;
  p.min_inliers = static_cast<size_t>(c.min_inliers);
  p.min_extent_m = c.min_extent_m;
  p.min_width_m = c.min_width_m;
  p.min_rows = c.min_rows;
  p.max_rms_m = c.max_rms_m;
  p.max_planes = c.max_planes;
  p.jump_base_m = c.jump_base_m;
  p.jump_factor = c.jump_factor;
  p.normal_neighbours = c.normal_neighbours;
  p.smoothness_deg = c.smoothness_deg;
  p.max_curvature = c.max_curvature;
  return p;
}

}  // namespace

extern "C" {

void mapd_plane_params_default(mapd_plane_params* c) {
  const mapd::robot::PlaneExtractionParams p;
  c->segmentation = p.segmentation == mapd::robot::PlaneSegmentation::kRegionGrowing ? 1 : 0;
  c->distance_m = p.distance_m;
  c->max_iterations = p.max_iterations;
  c->min_inliers = p.min_inliers;
  c->min_extent_m = p.min_extent_m;
  c->min_width_m = p.min_width_m;
  c->min_rows = p.min_rows;
  c->max_rms_m = p.max_rms_m;
  c->max_planes = p.max_planes;
  c->jump_base_m = p.jump_base_m;
  c->jump_factor = p.jump_factor;
  c->normal_neighbours = p.normal_neighbours;
  c->smoothness_deg = p.smoothness_deg;
  c->max_curvature = p.max_curvature;
}

int mapd_extract_planes(const float* xyz, size_t count, int rows, int columns, int wrap_columns,
                        const mapd_plane_params* params, mapd_planes** out, char* error,
                        size_t error_size) {
  using mapd::Status;
  if (out == nullptr) return Fail(Status::InvalidArgument("out is NULL"), error, error_size);
  *out = nullptr;
  if (xyz == nullptr && count > 0) {
    return Fail(Status::InvalidArgument("xyz is NULL"), error, error_size);
  }
  if (params != nullptr && params->segmentation != 0 && params->segmentation != 1) {
    return Fail(Status::InvalidArgument("plane extraction params: segmentation must be 0 "
                                        "(RANSAC) or 1 (region growing)"),
                error, error_size);
  }
  mapd_plane_params defaults;
  mapd_plane_params_default(&defaults);
  const mapd::robot::PlaneExtractionParams p = FromC(params != nullptr ? *params : defaults);
  try {  // no C++ exception crosses the C boundary (an allocation failure)
    std::vector<Eigen::Vector3f> points(count);
    for (size_t i = 0; i < count; ++i)
      points[i] = Eigen::Vector3f(xyz[3 * i], xyz[3 * i + 1], xyz[3 * i + 2]);
    auto planes = [&]() {
      if (rows == 0 && columns == 0) return mapd::robot::ExtractPlanes(points, p);
      mapd::robot::OrganisedCloud cloud;
      cloud.rows = rows;
      cloud.columns = columns;
      cloud.points = std::move(points);
      cloud.wrap_columns = wrap_columns != 0;
      return mapd::robot::ExtractPlanes(cloud, p);
    }();
    if (!planes.ok()) return Fail(planes.status(), error, error_size);
    *out = new mapd_planes{std::move(planes).value()};
    return 0;
  } catch (const std::exception& e) {
    return Fail(Status::Internal(std::string("plane extraction failed: ") + e.what()), error,
                error_size);
  }
}

size_t mapd_planes_count(const mapd_planes* planes) {
  return planes == nullptr ? 0 : planes->planes.size();
}

void mapd_planes_get(const mapd_planes* planes, size_t i, double normal[3], double* offset_m,
                     double* rms_m, size_t* boundary_size, size_t* inlier_count) {
  if (planes == nullptr || i >= planes->planes.size()) return;  // no exception crosses C
  const mapd::robot::ExtractedPlane& p = planes->planes[i];
  for (int k = 0; k < 3; ++k) normal[k] = p.feature.normal[k];
  *offset_m = p.feature.offset;
  *rms_m = p.rms_m;
  *boundary_size = p.feature.boundary.size();
  *inlier_count = p.indices.size();
}

void mapd_planes_boundary(const mapd_planes* planes, size_t i, double* xyz) {
  if (planes == nullptr || i >= planes->planes.size()) return;
  const auto& boundary = planes->planes[i].feature.boundary;
  for (size_t k = 0; k < boundary.size(); ++k) {
    for (int d = 0; d < 3; ++d) xyz[3 * k + static_cast<size_t>(d)] = boundary[k][d];
  }
}

void mapd_planes_inliers(const mapd_planes* planes, size_t i, int32_t* indices) {
  if (planes == nullptr || i >= planes->planes.size()) return;
  const auto& inliers = planes->planes[i].indices;
  std::copy(inliers.begin(), inliers.end(), indices);
}

void mapd_planes_free(mapd_planes* planes) { delete planes; }

int mapd_read_cloud(const char* path, mapd_cloud** out, char* error, size_t error_size) {
  using mapd::Status;
  if (out == nullptr || path == nullptr) {
    return Fail(Status::InvalidArgument("path or out is NULL"), error, error_size);
  }
  *out = nullptr;
  try {
    auto file = mapd::robot::ReadCloudFile(path);
    if (!file.ok()) return Fail(file.status(), error, error_size);
    *out = new mapd_cloud{std::move(file).value()};
    return 0;
  } catch (const std::exception& e) {
    return Fail(Status::Internal(std::string("reading ") + path + " failed: " + e.what()), error,
                error_size);
  }
}

size_t mapd_cloud_size(const mapd_cloud* cloud) {
  return cloud == nullptr ? 0 : cloud->file.points.size();
}

void mapd_cloud_shape(const mapd_cloud* cloud, int* rows, int* columns) {
  const bool organised = cloud != nullptr && cloud->file.organised();
  *rows = organised ? cloud->file.rows : 0;
  *columns = organised ? cloud->file.columns : 0;
}

const float* mapd_cloud_points(const mapd_cloud* cloud) {
  // Eigen::Vector3f is three packed floats (no alignment padding).
  static_assert(sizeof(Eigen::Vector3f) == 3 * sizeof(float));
  return cloud == nullptr || cloud->file.points.empty() ? nullptr
                                                        : cloud->file.points.front().data();
}

void mapd_cloud_free(mapd_cloud* cloud) { delete cloud; }

}  // extern "C"
