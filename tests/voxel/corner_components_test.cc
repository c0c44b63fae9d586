// Tests of the pieces of corner extraction that corner_extraction_test.cc only
// sees end to end: the voxel index, grid normals, planar region growing, the
// "three faces really meet" check and the working scale.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "voxel/corner_extraction.h"
#include "voxel/corner_faces.h"
#include "voxel/corner_voxel_index.h"
#include "voxel/normals_grid.h"
#include "voxel/plane_regions.h"
#include "voxel/voxel_grid.h"

namespace mapd::voxel::internal {
namespace {

Eigen::Vector3d Centre(const VoxelKey& k) {
  return k.cast<double>() + Eigen::Vector3d::Constant(0.5);
}

// Voxels whose centres lie within half_thickness of the plane n . p = d,
// inside the cube [lo, hi)^3 (voxels).
std::vector<VoxelKey> PlaneVoxels(const Eigen::Vector3d& n, double d, int lo, int hi,
                                  double half_thickness) {
  std::vector<VoxelKey> keys;
  for (int x = lo; x < hi; ++x)
    for (int y = lo; y < hi; ++y)
      for (int z = lo; z < hi; ++z)
        if (std::abs(n.dot(Centre(VoxelKey(x, y, z))) - d) <= half_thickness) {
          keys.emplace_back(x, y, z);
        }
  return keys;
}

// The three faces x = 0.5, y = 0.5, z = 0.5 (one voxel thick) of a concave
// corner at (0.5, 0.5, 0.5), each `size` voxels wide.
std::vector<VoxelKey> CornerVoxels(int size) {
  std::vector<VoxelKey> keys;
  for (int a = 0; a < size; ++a)
    for (int b = 0; b < size; ++b)
      for (int c = 0; c < size; ++c)
        if (a == 0 || b == 0 || c == 0) keys.emplace_back(a, b, c);
  return keys;
}

TEST(VoxelIndexTest, FindsEveryKeyAndEnumeratesCubesLikeBruteForce) {
  // Keys on both sides of zero and of brick boundaries.
  std::vector<VoxelKey> keys;
  for (int i = 0; i < 400; ++i) {
    keys.emplace_back((i * 37) % 29 - 14, (i * 11) % 23 - 9, (i * 7) % 19 - 12);
  }
  std::sort(keys.begin(), keys.end(), [](const VoxelKey& a, const VoxelKey& b) {
    return std::lexicographical_compare(a.data(), a.data() + 3, b.data(), b.data() + 3);
  });
  keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
  const VoxelIndex index(keys);
  for (std::size_t i = 0; i < keys.size(); ++i) EXPECT_EQ(index.Find(keys[i]), static_cast<int>(i));
  EXPECT_EQ(index.Find(VoxelKey(1000, 0, 0)), -1);
  for (const VoxelKey& centre : {VoxelKey(0, 0, 0), VoxelKey(-8, 7, -1), VoxelKey(3, -9, 5)}) {
    std::vector<int> seen;
    index.ForEachInCube(centre, 3, [&](int i, const VoxelKey& offset) {
      EXPECT_EQ(keys[static_cast<std::size_t>(i)] - centre, offset);
      seen.push_back(i);
    });
    std::vector<int> expected;
    for (std::size_t i = 0; i < keys.size(); ++i) {
      if ((keys[i] - centre).cwiseAbs().maxCoeff() <= 3) expected.push_back(static_cast<int>(i));
    }
    std::sort(seen.begin(), seen.end());
    EXPECT_EQ(seen, expected);
  }
  // Dense windows across brick boundaries and zero agree with Find.
  for (const VoxelKey& lo : {VoxelKey(-10, -10, -13), VoxelKey(-3, 2, -6), VoxelKey(5, -9, 0)}) {
    const int edge = 12;
    std::vector<std::uint8_t> window(edge * edge * edge, 7);
    index.FillOccupancy(lo, edge, window.data());
    for (int x = 0; x < edge; ++x) {
      for (int y = 0; y < edge; ++y) {
        for (int z = 0; z < edge; ++z) {
          const bool occupied = index.Find(lo + VoxelKey(x, y, z)) >= 0;
          ASSERT_EQ(window[static_cast<std::size_t>((x * edge + y) * edge + z)], occupied ? 1 : 0)
              << "window at " << lo.transpose() << ", cell " << x << " " << y << " " << z;
        }
      }
    }
  }
}

TEST(GridNormalsTest, TiltedPlaneGivesItsNormalAndLowCurvature) {
  const Eigen::Vector3d n = Eigen::Vector3d(0.3, -0.5, 0.8).normalized();
  const std::vector<VoxelKey> keys = PlaneVoxels(n, 2.0, -12, 12, 0.6);
  const VoxelIndex index(keys);
  const GridNormals normals = ComputeGridNormals(keys, index, 2.5);
  ASSERT_EQ(normals.normals.size(), keys.size());
  int interior = 0;
  for (std::size_t i = 0; i < keys.size(); ++i) {
    if (keys[i].cwiseAbs().maxCoeff() > 8) continue;  // away from the cube's cut
    ++interior;
    EXPECT_NEAR(normals.normals[i].norm(), 1.0f, 1e-5f);
    // A rasterised plane's local normal is good to a few degrees.
    EXPECT_GT(std::abs(normals.normals[i].cast<double>().dot(n)), std::cos(8.0 * M_PI / 180.0));
    EXPECT_LT(normals.curvature[i], 0.05f);
  }
  EXPECT_GT(interior, 100);
}

TEST(GridNormalsTest, IsolatedVoxelHasCurvatureOne) {
  const std::vector<VoxelKey> keys = {VoxelKey(0, 0, 0), VoxelKey(10, 0, 0)};
  const VoxelIndex index(keys);
  const GridNormals normals = ComputeGridNormals(keys, index, 2.5);
  EXPECT_EQ(normals.curvature[0], 1.0f);
  EXPECT_EQ(normals.curvature[1], 1.0f);
}

TEST(PlaneRegionsTest, CornerFacesBecomeThreeSeparatePlanes) {
  const std::vector<VoxelKey> keys = CornerVoxels(20);
  const VoxelIndex index(keys);
  const GridNormals normals = ComputeGridNormals(keys, index, 2.5);
  PlaneRegionParams params;
  params.smoothness_deg = 20.0;
  params.curvature_threshold = 0.25;
  params.max_plane_distance = 2.0;
  params.max_plane_rms = 1.2;
  const PlaneRegions regions = GrowPlaneRegions(keys, index, normals, params);
  ASSERT_EQ(regions.planes.size(), 3u);
  std::array<bool, 3> axis_seen{};
  for (const FittedPlane& plane : regions.planes) {
    int axis = 0;
    plane.normal.cwiseAbs().maxCoeff(&axis);
    EXPECT_GT(std::abs(plane.normal(axis)), 0.999);
    EXPECT_NEAR(std::abs(plane.offset), 0.5, 1e-6);  // the face x = 0.5 etc.
    EXPECT_LT(plane.rms, 1e-6);
    axis_seen[static_cast<std::size_t>(axis)] = true;
  }
  EXPECT_TRUE(axis_seen[0] && axis_seen[1] && axis_seen[2]);
  // A labelled voxel is on its plane.
  for (std::size_t i = 0; i < keys.size(); ++i) {
    if (regions.label[i] < 0) continue;
    EXPECT_LT(regions.planes[static_cast<std::size_t>(regions.label[i])].Distance(Centre(keys[i])),
              1e-6);
  }
}

TEST(PlaneRegionsTest, RegionsDoNotCreepRoundACylinder) {
  // A cylinder of radius 12 voxels: every neighbour-to-neighbour step is
  // smooth, but no region may span more than the region angle of its surface.
  std::vector<VoxelKey> keys;
  for (int x = -14; x <= 14; ++x)
    for (int y = -14; y <= 14; ++y)
      for (int z = 0; z < 20; ++z)
        if (std::abs(std::hypot(x + 0.5, y + 0.5) - 12.0) <= 0.6) keys.emplace_back(x, y, z);
  const VoxelIndex index(keys);
  const GridNormals normals = ComputeGridNormals(keys, index, 2.5);
  PlaneRegionParams params;
  params.smoothness_deg = 20.0;
  params.region_angle_deg = 15.0;
  params.curvature_threshold = 0.25;
  params.max_plane_rms = 10.0;  // keep every region to look at its extent
  const PlaneRegions regions = GrowPlaneRegions(keys, index, normals, params);
  ASSERT_GT(regions.planes.size(), 2u);
  for (std::size_t p = 0; p < regions.planes.size(); ++p) {
    double min_angle = 10, max_angle = -10;
    for (std::size_t i = 0; i < keys.size(); ++i) {
      if (regions.label[i] != static_cast<int>(p)) continue;
      const double a = std::atan2(keys[i].y() + 0.5, keys[i].x() + 0.5);
      min_angle = std::min(min_angle, a);
      max_angle = std::max(max_angle, a);
    }
    // Across the +-pi seam the extent is measured the other way round.
    double extent = max_angle - min_angle;
    if (extent > M_PI) extent = 2 * M_PI - extent;
    EXPECT_LT(extent * 180.0 / M_PI, 75.0) << p;
  }
}

TEST(CornerFacesTest, ThreeFacesOfACornerMeetAtTheCorner) {
  const std::vector<VoxelKey> keys = CornerVoxels(12);
  const VoxelIndex index(keys);
  std::array<FittedPlane, 3> planes;
  for (int k = 0; k < 3; ++k) {
    planes[static_cast<std::size_t>(k)].normal = Eigen::Vector3d::Unit(k);
    planes[static_cast<std::size_t>(k)].offset = -0.5;
  }
  // Start from planes a little off: the local refit pulls them back.
  planes[0].normal = Eigen::Vector3d(1.0, 0.05, -0.03).normalized();
  planes[0].offset = -0.9;
  MeetingFaces faces;
  ASSERT_TRUE(FacesMeet(keys, index, planes, FaceParams{}, &faces));
  EXPECT_LT((faces.position - Eigen::Vector3d::Constant(0.5)).norm(), 0.05);
  for (int k = 0; k < 3; ++k) EXPECT_GE(faces.support[static_cast<std::size_t>(k)], 8);
}

TEST(CornerFacesTest, PlanesThatCrossWhereAFaceIsMissingDoNotMeet) {
  // Only two faces have voxels: the third plane (z = 0.5) crosses them on
  // their common edge, but has no voxels of its own there.
  std::vector<VoxelKey> keys;
  for (const VoxelKey& k : CornerVoxels(12)) {
    if (k.x() == 0 || k.y() == 0) keys.push_back(k);
  }
  const VoxelIndex index(keys);
  std::array<FittedPlane, 3> planes;
  for (int k = 0; k < 3; ++k) {
    planes[static_cast<std::size_t>(k)].normal = Eigen::Vector3d::Unit(k);
    planes[static_cast<std::size_t>(k)].offset = -0.5;
  }
  MeetingFaces faces;
  EXPECT_FALSE(FacesMeet(keys, index, planes, FaceParams{}, &faces));
}

TEST(CornerFacesTest, NearlyDependentNormalsDoNotIntersect) {
  std::array<FittedPlane, 3> planes;
  planes[0].normal = Eigen::Vector3d::UnitX();
  planes[1].normal = Eigen::Vector3d::UnitY();
  planes[2].normal = Eigen::Vector3d(1.0, 1.0, 0.05).normalized();  // pairwise 45 deg
  Eigen::Vector3d point;
  EXPECT_FALSE(IntersectPlanes(planes, 0.1, &point));
  planes[2].normal = Eigen::Vector3d::UnitZ();
  EXPECT_TRUE(IntersectPlanes(planes, 0.1, &point));
}

}  // namespace
}  // namespace mapd::voxel::internal

namespace mapd::voxel {
namespace {

// The shell of a box two voxels thick (a coarse voxel per 2^3 fine ones at
// scale 2 sees a one-voxel shell): corners at scale 2 land within a fine voxel
// of the thick shell's mid-surface corners.
TEST(CornerExtractionScaleTest, CoarseScaleFindsTheCornersOfAThickBox) {
  std::vector<VoxelKey> keys;
  const VoxelKey size(48, 40, 32);
  for (int x = 0; x < size.x(); ++x)
    for (int y = 0; y < size.y(); ++y)
      for (int z = 0; z < size.z(); ++z)
        if (x < 2 || y < 2 || z < 2 || x >= size.x() - 2 || y >= size.y() - 2 ||
            z >= size.z() - 2) {
          keys.emplace_back(x, y, z);
        }
  StatusOr<VoxelGrid> grid = VoxelGrid::FromKeys(0.05, keys);
  ASSERT_TRUE(grid.ok());
  CornerExtractionParams params;
  params.scale = 2;
  StatusOr<CornerExtractionResult> result = ExtractCorners(*grid, params);
  ASSERT_TRUE(result.ok()) << result.status().ToString();
  EXPECT_EQ(result->scale, 2);
  EXPECT_LT(result->working_voxels, grid->num_occupied() / 4);
  ASSERT_EQ(result->corners.size(), 8u);
  for (const Corner& c : result->corners) {
    // Mid-surface of the two-voxel shell: 1 voxel in from each outer face.
    const Eigen::Vector3d v = c.position / 0.05;
    for (int a = 0; a < 3; ++a) {
      const double lo = 1.0, hi = size(a) - 1.0;
      EXPECT_LT(std::min(std::abs(v(a) - lo), std::abs(v(a) - hi)), 1.0) << v.transpose();
    }
  }
}

TEST(CornerExtractionScaleTest, ValidateNamesTheNewFields) {
  CornerExtractionParams params;
  params.scale = 0;
  EXPECT_NE(params.Validate().message().find("scale"), std::string::npos);
  params = {};
  params.region_angle_deg = 95.0;
  EXPECT_NE(params.Validate().message().find("region_angle_deg"), std::string::npos);
  params = {};
  params.min_face_support = 1;
  EXPECT_NE(params.Validate().message().find("min_face_support"), std::string::npos);
  params = {};
  params.face_band = -1.0;
  EXPECT_NE(params.Validate().message().find("face_band"), std::string::npos);
  params = {};
  params.min_normal_determinant = 0.0;
  EXPECT_NE(params.Validate().message().find("min_normal_determinant"), std::string::npos);
  params = {};
  params.max_planes_per_candidate = 2;
  EXPECT_NE(params.Validate().message().find("max_planes_per_candidate"), std::string::npos);
  EXPECT_TRUE(CornerExtractionParams{}.Validate().ok());
}

}  // namespace
}  // namespace mapd::voxel
