#include "bench/fpfh_baseline.h"

#include <pcl/features/fpfh_omp.h>
#include <pcl/features/normal_3d_omp.h>
#include <pcl/filters/voxel_grid.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>
#include <pcl/registration/icp.h>
#include <pcl/registration/sample_consensus_prerejective.h>
#include <pcl/search/kdtree.h>

#include <chrono>
#include <cmath>
#include <cstdlib>

namespace mapd::bench {
namespace {

using PointT = pcl::PointNormal;
using Cloud = pcl::PointCloud<PointT>;
using Features = pcl::PointCloud<pcl::FPFHSignature33>;

double Since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

Cloud::Ptr ToCloud(const std::vector<Eigen::Vector3d>& points) {
  Cloud::Ptr cloud(new Cloud);
  cloud->reserve(points.size());
  for (const Eigen::Vector3d& p : points) {
    PointT q;
    q.x = static_cast<float>(p.x());
    q.y = static_cast<float>(p.y());
    q.z = static_cast<float>(p.z());
    cloud->push_back(q);
  }
  return cloud;
}

Cloud::Ptr Downsample(const Cloud::Ptr& in, double leaf) {
  pcl::VoxelGrid<PointT> grid;
  grid.setLeafSize(static_cast<float>(leaf), static_cast<float>(leaf), static_cast<float>(leaf));
  grid.setInputCloud(in);
  Cloud::Ptr out(new Cloud);
  grid.filter(*out);
  return out;
}

// Normals, then the points whose normal could not be estimated (too few
// neighbours) are dropped: FPFH of a NaN normal is NaN.
Cloud::Ptr WithNormals(const Cloud::Ptr& in, double radius, int threads) {
  pcl::NormalEstimationOMP<PointT, PointT> ne(threads);
  ne.setRadiusSearch(radius);
  ne.setInputCloud(in);
  ne.compute(*in);
  Cloud::Ptr out(new Cloud);
  out->reserve(in->size());
  for (const PointT& p : *in) {
    if (std::isfinite(p.normal_x) && std::isfinite(p.normal_y) && std::isfinite(p.normal_z)) {
      out->push_back(p);
    }
  }
  return out;
}

Features::Ptr Fpfh(const Cloud::Ptr& cloud, double radius, int threads) {
  pcl::FPFHEstimationOMP<PointT, PointT, pcl::FPFHSignature33> fe(threads);
  fe.setRadiusSearch(radius);
  fe.setInputCloud(cloud);
  fe.setInputNormals(cloud);
  Features::Ptr features(new Features);
  fe.compute(*features);
  return features;
}

}  // namespace

Status FpfhParams::Validate() const {
  if (!(leaf_voxels >= 1.0 && leaf_voxels <= 20.0)) {
    return Status::InvalidArgument("leaf_voxels must be in [1, 20]");
  }
  if (!(normal_radius_leaves > 0.0))
    return Status::InvalidArgument("normal_radius_leaves must be > 0");
  if (!(feature_radius_leaves > normal_radius_leaves)) {
    return Status::InvalidArgument("feature_radius_leaves must exceed normal_radius_leaves");
  }
  if (max_iterations < 1) return Status::InvalidArgument("max_iterations must be >= 1");
  if (num_samples < 3) return Status::InvalidArgument("num_samples must be >= 3");
  if (correspondence_randomness < 1) {
    return Status::InvalidArgument("correspondence_randomness must be >= 1");
  }
  if (!(similarity_threshold >= 0.0 && similarity_threshold < 1.0)) {
    return Status::InvalidArgument("similarity_threshold must be in [0, 1)");
  }
  if (!(max_correspondence_leaves > 0.0)) {
    return Status::InvalidArgument("max_correspondence_leaves must be > 0");
  }
  if (!(inlier_fraction > 0.0 && inlier_fraction <= 1.0)) {
    return Status::InvalidArgument("inlier_fraction must be in (0, 1]");
  }
  if (!(icp_max_correspondence_voxels > 0.0)) {
    return Status::InvalidArgument("icp_max_correspondence_voxels must be > 0");
  }
  if (icp_max_iterations < 0) return Status::InvalidArgument("icp_max_iterations must be >= 0");
  if (threads < 1) return Status::InvalidArgument("threads must be >= 1");
  return Status::Ok();
}

StatusOr<FpfhResult> AlignFpfh(const std::vector<Eigen::Vector3d>& a,
                               const std::vector<Eigen::Vector3d>& b, double resolution,
                               const FpfhParams& params) {
  MAPD_RETURN_IF_ERROR(params.Validate());
  if (!(std::isfinite(resolution) && resolution > 0.0)) {
    return Status::InvalidArgument("resolution must be finite and > 0");
  }
  if (a.empty() || b.empty()) return Status::InvalidArgument("empty point cloud");
  const double leaf = params.leaf_voxels * resolution;
  FpfhResult result;

  auto start = std::chrono::steady_clock::now();
  const Cloud::Ptr full_a = ToCloud(a), full_b = ToCloud(b);
  Cloud::Ptr down_a = Downsample(full_a, leaf), down_b = Downsample(full_b, leaf);
  result.times.downsample_s = Since(start);

  start = std::chrono::steady_clock::now();
  down_a = WithNormals(down_a, params.normal_radius_leaves * leaf, params.threads);
  down_b = WithNormals(down_b, params.normal_radius_leaves * leaf, params.threads);
  result.times.normals_s = Since(start);
  result.points_a = down_a->size();
  result.points_b = down_b->size();
  if (down_a->size() < 3 || down_b->size() < 3) return result;  // nothing to align: refuse

  start = std::chrono::steady_clock::now();
  const Features::Ptr feat_a = Fpfh(down_a, params.feature_radius_leaves * leaf, params.threads);
  const Features::Ptr feat_b = Fpfh(down_b, params.feature_radius_leaves * leaf, params.threads);
  result.times.features_s = Since(start);

  start = std::chrono::steady_clock::now();
  std::srand(params.seed);
  pcl::SampleConsensusPrerejective<PointT, PointT, pcl::FPFHSignature33> align;
  align.setInputSource(down_b);
  align.setSourceFeatures(feat_b);
  align.setInputTarget(down_a);
  align.setTargetFeatures(feat_a);
  align.setMaximumIterations(params.max_iterations);
  align.setNumberOfSamples(params.num_samples);
  align.setCorrespondenceRandomness(params.correspondence_randomness);
  align.setSimilarityThreshold(static_cast<float>(params.similarity_threshold));
  align.setMaxCorrespondenceDistance(params.max_correspondence_leaves * leaf);
  align.setInlierFraction(static_cast<float>(params.inlier_fraction));
  Cloud aligned;
  align.align(aligned);
  result.times.ransac_s = Since(start);
  if (!align.hasConverged()) return result;
  result.ransac_inlier_fraction =
      static_cast<double>(align.getInliers().size()) / static_cast<double>(down_b->size());
  const Eigen::Matrix4f guess = align.getFinalTransformation();

  start = std::chrono::steady_clock::now();
  Eigen::Matrix4f final_T = guess;
  if (params.icp_max_iterations > 0) {
    pcl::IterativeClosestPoint<PointT, PointT> icp;
    icp.setInputSource(params.icp_full_resolution ? full_b : down_b);
    icp.setInputTarget(params.icp_full_resolution ? full_a : down_a);
    icp.setMaxCorrespondenceDistance(params.icp_max_correspondence_voxels * resolution);
    icp.setMaximumIterations(params.icp_max_iterations);
    icp.setTransformationEpsilon(1e-9);
    icp.setEuclideanFitnessEpsilon(1e-8);
    Cloud refined;
    icp.align(refined, guess);
    if (icp.hasConverged()) {
      final_T = icp.getFinalTransformation();
      result.icp_fitness_m2 =
          icp.getFitnessScore(params.icp_max_correspondence_voxels * resolution);
    }
  }
  result.times.icp_s = Since(start);
  result.accepted = true;
  result.T_a_b.matrix() = final_T.cast<double>();
  // Re-orthonormalise: the float matrix is only approximately a rotation.
  const Eigen::Matrix3d R = result.T_a_b.linear();
  result.T_a_b.linear() = Eigen::Quaterniond(R).normalized().toRotationMatrix();
  return result;
}

}  // namespace mapd::bench
