#include "voxel/submap_features.h"

#include <algorithm>
#include <chrono>
#include <string>
#include <utility>

#include "common/clock.h"
#include "voxel/corner_extraction.h"
#include "voxel/gravity_alignment.h"
#include "voxel/memory_bytes.h"

namespace mapd::voxel {

StatusOr<const CornerSet*> SubmapFeatures::Corners(StageTimes* times) {
  corners_used_ = true;
  if (!corners_.has_value()) {
    const auto start = std::chrono::steady_clock::now();
    // The shared normals when they are the ones corner extraction uses (and
    // the map is within its limit, which it checks first).
    const CornerExtractionParams& corners = params_->corners;
    const bool shared = corners.scale == 1 && corners.normal_radius == kGravityNormalRadiusVoxels &&
                        grid_->num_occupied() <= corners.max_occupied_voxels;
    auto result = ExtractCorners(*grid_, corners, shared ? &Surface() : nullptr);
    times->corners_s += SecondsSince(start);
    if (!result.ok()) {
      return Status(result.status().code(),
                    "submap " + std::to_string(id_) + ": " + result.status().message());
    }
    corners_ = std::move(result->corners);
  }
  return &*corners_;
}

const StatusOr<GravityFrame>& SubmapFeatures::Gravity(StageTimes* times) {
  if (!gravity_.has_value()) {
    const auto start = std::chrono::steady_clock::now();
    gravity_ = EstimateGravityFrame(*grid_, params_->gravity, &Surface());
    times->correlation_s += SecondsSince(start);
  }
  return *gravity_;
}

const internal::GridSurface& SubmapFeatures::Surface() {
  if (!surface_.has_value()) {
    surface_.emplace(grid_->occupied_keys(), kGravityNormalRadiusVoxels);
  }
  return *surface_;
}

const OverlapIndex& SubmapFeatures::Overlap() {
  if (!overlap_.has_value()) overlap_.emplace(*grid_);
  return *overlap_;
}

const IcpTarget& SubmapFeatures::IcpIndex(double voxel_size_m) {
  if (icp_target_ == nullptr || icp_target_->voxel_size_m() != voxel_size_m) {
    icp_target_ = std::make_unique<IcpTarget>(&grid_->occupied_centres(), voxel_size_m);
  }
  return *icp_target_;
}

const Eigen::Vector3d& SubmapFeatures::OccupiedCentroid() {
  if (!centroid_.has_value()) {
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    for (const Eigen::Vector3d& c : grid_->occupied_centres()) sum += c;
    centroid_ = sum / static_cast<double>(std::max<std::size_t>(1, grid_->num_occupied()));
  }
  return *centroid_;
}

std::size_t SubmapFeatures::MemoryBytes() const {
  std::size_t bytes = 0;
  if (corners_.has_value()) bytes += voxel::MemoryBytes(*corners_);
  if (surface_.has_value()) {
    bytes += surface_->index.MemoryBytes() + voxel::MemoryBytes(surface_->normals.normals) +
             voxel::MemoryBytes(surface_->normals.curvature);
  }
  if (overlap_.has_value()) bytes += overlap_->MemoryBytes();
  if (icp_target_ != nullptr) bytes += icp_target_->MemoryBytes();
  return bytes;
}

}  // namespace mapd::voxel
