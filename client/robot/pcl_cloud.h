// PCL point clouds as the plane extractor takes them, for a robot whose
// driver already gives pcl::PointCloud<PointT> (any type with x y z:
// PointXYZ, PointXYZI, PointXYZRGB, ...). Header-only; include it where PCL
// is already included.
#ifndef MAPD_CLIENT_ROBOT_PCL_CLOUD_H_
#define MAPD_CLIENT_ROBOT_PCL_CLOUD_H_

#include <pcl/point_cloud.h>

#include <Eigen/Core>
#include <vector>

#include "client/robot/cloud_planes.h"

namespace mapd::robot {

// Every point's x y z, in the cloud's order.
template <typename PointT>
std::vector<Eigen::Vector3f> ToPoints(const pcl::PointCloud<PointT>& cloud) {
  std::vector<Eigen::Vector3f> points;
  points.reserve(cloud.size());
  for (const PointT& p : cloud) points.emplace_back(p.x, p.y, p.z);
  return points;
}

// An organised cloud (height > 1: one row per beam or image row) as an
// OrganisedCloud; wrap_columns for a 360 degree LiDAR.
template <typename PointT>
OrganisedCloud ToOrganisedCloud(const pcl::PointCloud<PointT>& cloud, bool wrap_columns) {
  OrganisedCloud out;
  out.rows = static_cast<int>(cloud.height);
  out.columns = static_cast<int>(cloud.width);
  out.points = ToPoints(cloud);
  out.wrap_columns = wrap_columns;
  return out;
}

}  // namespace mapd::robot

#endif  // MAPD_CLIENT_ROBOT_PCL_CLOUD_H_
