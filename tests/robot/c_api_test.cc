// The C interface (libmapd_robot_c) as a C caller uses it: the room's planes
// through it, and misuse (NULL handles, an index out of range, bad settings)
// answered without an exception or a crash.
#include "client/robot/c_api.h"

#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "robot/room_scan.h"

namespace mapd::robot {
namespace {

TEST(CApiTest, TheRoomsPlanesAndMisuseAnsweredQuietly) {
  std::vector<float> xyz;
  for (const Eigen::Vector3f& p : scenes::DenseRoom()) xyz.insert(xyz.end(), {p.x(), p.y(), p.z()});
  mapd_planes* planes = nullptr;
  char error[256] = "";
  ASSERT_EQ(mapd_extract_planes(xyz.data(), xyz.size() / 3, 0, 0, 0, nullptr, &planes, error,
                                sizeof error),
            0)
      << error;
  ASSERT_EQ(mapd_planes_count(planes), 2U);
  double normal[3] = {7, 7, 7}, offset = 7, rms = 7;
  size_t boundary = 7, inliers = 7;
  mapd_planes_get(planes, 0, normal, &offset, &rms, &boundary, &inliers);
  EXPECT_NEAR(std::hypot(normal[0], normal[1], normal[2]), 1.0, 1e-9);
  EXPECT_GE(boundary, 3U);
  normal[0] = 7;
  mapd_planes_get(planes, 2, normal, &offset, &rms, &boundary, &inliers);  // out of range
  EXPECT_EQ(normal[0], 7);
  mapd_planes_boundary(planes, 99, nullptr);
  mapd_planes_inliers(planes, 99, nullptr);
  mapd_planes_free(planes);

  EXPECT_EQ(mapd_planes_count(nullptr), 0U);
  EXPECT_EQ(mapd_cloud_size(nullptr), 0U);
  EXPECT_EQ(mapd_cloud_points(nullptr), nullptr);
  int rows = 7, columns = 7;
  mapd_cloud_shape(nullptr, &rows, &columns);
  EXPECT_EQ(rows, 0);
  mapd_plane_params params;
  mapd_plane_params_default(&params);
  params.distance_m = NAN;
  EXPECT_EQ(mapd_extract_planes(xyz.data(), xyz.size() / 3, 0, 0, 0, &params, &planes, error,
                                sizeof error),
            1);
  EXPECT_NE(std::string(error).find("distance_m"), std::string::npos) << error;
  EXPECT_EQ(planes, nullptr);
  EXPECT_EQ(mapd_extract_planes(nullptr, 5, 0, 0, 0, nullptr, &planes, error, sizeof error), 1);
  mapd_cloud* cloud = nullptr;
  EXPECT_EQ(mapd_read_cloud("/no/such/scan.pcd", &cloud, error, 8), 2);
  EXPECT_EQ(std::string(error), "cannot ");  // cut to the buffer, NUL-terminated
}

}  // namespace
}  // namespace mapd::robot
