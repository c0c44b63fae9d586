// Corner extraction (voxel/corner_extraction.h) on generated boxes and rooms
// whose corners are known.
#include "voxel/corner_extraction.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <vector>

#include "voxel/voxel_grid.h"

namespace mapd::voxel {
namespace {

constexpr double kRes = 0.1;

// A generated map and the corners it has (metres).
struct Scene {
  std::vector<VoxelKey> occupied;
  std::vector<VoxelKey> free;
  std::vector<Eigen::Vector3d> corners;
};

VoxelGrid Grid(const Scene& scene) {
  StatusOr<VoxelGrid> grid = VoxelGrid::FromKeys(kRes, scene.occupied, scene.free);
  EXPECT_TRUE(grid.ok()) << grid.status().ToString();
  return std::move(grid).value();
}

// The one-voxel shell of the box [0, size) (keys); its faces' voxel centres lie
// on the planes x = 0.5 and x = size - 0.5 (voxels), so those meet at the corners.
Scene AxisAlignedBox(const VoxelKey& size, const VoxelKey& origin) {
  Scene scene;
  for (int x = 0; x < size.x(); ++x) {
    for (int y = 0; y < size.y(); ++y) {
      for (int z = 0; z < size.z(); ++z) {
        const bool shell = x == 0 || y == 0 || z == 0 || x == size.x() - 1 || y == size.y() - 1 ||
                           z == size.z() - 1;
        if (shell) scene.occupied.push_back(origin + VoxelKey(x, y, z));
      }
    }
  }
  for (int c = 0; c < 8; ++c) {
    const Eigen::Vector3d lo = origin.cast<double>() + Eigen::Vector3d::Constant(0.5);
    const Eigen::Vector3d hi = (origin + size).cast<double>() - Eigen::Vector3d::Constant(0.5);
    scene.corners.emplace_back(((c & 1) ? hi.x() : lo.x()) * kRes,
                               ((c & 2) ? hi.y() : lo.y()) * kRes,
                               ((c & 4) ? hi.z() : lo.z()) * kRes);
  }
  return scene;
}

// Voxels whose centres lie within half_thickness (voxels) of the surface of
// the box of `half_extent` (voxels) centred at `centre`, rotated by R.
Scene RotatedBox(const Eigen::Matrix3d& R, const Eigen::Vector3d& centre,
                 const Eigen::Vector3d& half_extent, double half_thickness) {
  Scene scene;
  const double reach = half_extent.norm() + 2.0;
  for (int x = static_cast<int>(std::floor(centre.x() - reach)); x <= centre.x() + reach; ++x) {
    for (int y = static_cast<int>(std::floor(centre.y() - reach)); y <= centre.y() + reach; ++y) {
      for (int z = static_cast<int>(std::floor(centre.z() - reach)); z <= centre.z() + reach; ++z) {
        const Eigen::Vector3d q =
            R.transpose() * (Eigen::Vector3d(x + 0.5, y + 0.5, z + 0.5) - centre);
        // Signed distance to the box surface.
        const Eigen::Vector3d d = q.cwiseAbs() - half_extent;
        const double outside = d.cwiseMax(0.0).norm();
        const double sd = outside > 0.0 ? outside : d.maxCoeff();
        if (std::abs(sd) <= half_thickness) scene.occupied.emplace_back(x, y, z);
      }
    }
  }
  for (int c = 0; c < 8; ++c) {
    const Eigen::Vector3d s((c & 1) ? 1 : -1, (c & 2) ? 1 : -1, (c & 4) ? 1 : -1);
    scene.corners.push_back((centre + R * s.cwiseProduct(half_extent)) * kRes);
  }
  return scene;
}

// An L-shaped room seen from inside: floor, ceiling and walls one voxel thick
// around the free interior {x < 30, y < 12} u {x < 12, y < 30}, z in [0, 10).
// The walls' voxel centres lie at -0.5 and at the far side + 0.5, so the room
// has 12 corners: 6 footprint vertices (5 convex, 1 reflex) at floor and ceiling.
Scene LRoom() {
  const int a = 30, b = 12, h = 10;
  auto inside = [&](int x, int y, int z) {
    return z >= 0 && z < h && x >= 0 && y >= 0 && ((x < a && y < b) || (x < b && y < a));
  };
  Scene scene;
  for (int x = -1; x <= a; ++x) {
    for (int y = -1; y <= a; ++y) {
      for (int z = -1; z <= h; ++z) {
        if (inside(x, y, z)) {
          scene.free.emplace_back(x, y, z);
          continue;
        }
        bool near = false;
        for (int dx = -1; dx <= 1; ++dx)
          for (int dy = -1; dy <= 1; ++dy)
            for (int dz = -1; dz <= 1; ++dz) near = near || inside(x + dx, y + dy, z + dz);
        if (near) scene.occupied.emplace_back(x, y, z);
      }
    }
  }
  const double xs[] = {-0.5, a + 0.5, a + 0.5, b + 0.5, b + 0.5, -0.5};
  const double ys[] = {-0.5, -0.5, b + 0.5, b + 0.5, a + 0.5, a + 0.5};
  for (int i = 0; i < 6; ++i) {
    for (double z : {-0.5, h + 0.5})
      scene.corners.emplace_back(xs[i] * kRes, ys[i] * kRes, z * kRes);
  }
  return scene;
}

struct Score {
  int found = 0;          // true corners with a detected corner within 1 voxel
  int false_corners = 0;  // detected corners not within 1.5 voxels of a true one
  double max_error = 0;   // voxels, over the found corners
};

Score Evaluate(const CornerSet& detected, const std::vector<Eigen::Vector3d>& truth) {
  Score score;
  for (const Eigen::Vector3d& t : truth) {
    double best = 1e9;
    for (const Corner& c : detected) best = std::min(best, (c.position - t).norm() / kRes);
    if (best < 1.0) {
      ++score.found;
      score.max_error = std::max(score.max_error, best);
    }
  }
  for (const Corner& c : detected) {
    double best = 1e9;
    for (const Eigen::Vector3d& t : truth) best = std::min(best, (c.position - t).norm() / kRes);
    if (best > 1.5) ++score.false_corners;
  }
  return score;
}

CornerExtractionResult Extract(const Scene& scene, const CornerExtractionParams& params = {}) {
  StatusOr<CornerExtractionResult> result = ExtractCorners(Grid(scene), params);
  EXPECT_TRUE(result.ok()) << result.status().ToString();
  return result.ok() ? std::move(result).value() : CornerExtractionResult{};
}

TEST(CornerExtractionTest, FindsTheCornersOfAnAxisAlignedBox) {
  const Scene box = AxisAlignedBox(VoxelKey(24, 18, 14), VoxelKey(-7, 3, -2));
  const CornerExtractionResult result = Extract(box);
  const Score score = Evaluate(result.corners, box.corners);
  EXPECT_EQ(score.found, 8);
  EXPECT_EQ(score.false_corners, 0);
  EXPECT_LT(score.max_error, 1.0);
  EXPECT_EQ(result.corners.size(), 8u);
  EXPECT_GE(result.candidates, 8u);
  EXPECT_GE(result.planes, 6u);
}

TEST(CornerExtractionTest, BoxNormalsAreUnitPairwiseOrthogonalAndOutward) {
  const Scene box = AxisAlignedBox(VoxelKey(20, 20, 16), VoxelKey(0, 0, 0));
  const CornerExtractionResult result = Extract(box);
  const Eigen::Vector3d centre(1.0, 1.0, 0.8);
  // All eight, as for the box above: a loop over none would prove nothing.
  ASSERT_EQ(result.corners.size(), 8u);
  for (const Corner& corner : result.corners) {
    for (int i = 0; i < 3; ++i) {
      EXPECT_NEAR(corner.normals[i].norm(), 1.0, 1e-9);
      // No free space known: normals point away from the other faces (outward here).
      EXPECT_GT(corner.normals[i].dot(corner.position - centre), 0.0);
      for (int j = i + 1; j < 3; ++j)
        EXPECT_LT(std::abs(corner.normals[i].dot(corner.normals[j])), 0.05);
    }
    EXPECT_GT(corner.support, 0);
  }
}

TEST(CornerExtractionTest, FindsTheCornersOfRotatedBoxes) {
  const Eigen::Matrix3d rotations[] = {
      (Eigen::AngleAxisd(0.5, Eigen::Vector3d::UnitZ()) *
       Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitX()))
          .toRotationMatrix(),
      Eigen::AngleAxisd(0.9, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix()};
  const Eigen::Vector3d half_extents[] = {Eigen::Vector3d(12, 9, 7), Eigen::Vector3d(15, 10, 8)};
  for (int i = 0; i < 2; ++i) {
    const Scene box =
        RotatedBox(rotations[i], Eigen::Vector3d(3.2, -1.7, 5.4), half_extents[i], 0.6);
    const CornerExtractionResult result = Extract(box);
    const Score score = Evaluate(result.corners, box.corners);
    EXPECT_EQ(score.found, 8) << i;
    EXPECT_EQ(score.false_corners, 0) << i;
    EXPECT_EQ(result.corners.size(), 8u) << i;
    EXPECT_LT(score.max_error, 1.0) << i;
  }
}

TEST(CornerExtractionTest, FindsTheCornersOfAnLShapedRoom) {
  const Scene room = LRoom();
  const CornerExtractionResult result = Extract(room);
  const Score score = Evaluate(result.corners, room.corners);
  EXPECT_EQ(score.found, 12);
  EXPECT_EQ(score.false_corners, 0);
  EXPECT_LT(score.max_error, 1.0);
  // Free space inside: every normal points into the room (away from the
  // occupied side), so stepping along all three from a corner lands inside.
  const VoxelGrid grid = Grid(room);
  for (const Corner& corner : result.corners) {
    const Eigen::Vector3d step = corner.normals[0] + corner.normals[1] + corner.normals[2];
    EXPECT_EQ(grid.State(grid.PointToKey(corner.position + 3.0 * kRes * step)), VoxelState::kFree)
        << corner.position.transpose();
  }
}

TEST(CornerExtractionTest, EmptyMapAndSinglePlaneGiveNoCorners) {
  const CornerExtractionResult empty = Extract(Scene{});
  EXPECT_TRUE(empty.corners.empty());
  EXPECT_EQ(empty.candidates, 0u);

  Scene plane;
  for (int x = 0; x < 40; ++x)
    for (int y = 0; y < 30; ++y) plane.occupied.emplace_back(x, y, 5);
  const CornerExtractionResult flat = Extract(plane);
  EXPECT_TRUE(flat.corners.empty());
  EXPECT_EQ(flat.verified_candidates, 0u);

  Scene single;
  single.occupied.emplace_back(1, 2, 3);
  EXPECT_TRUE(Extract(single).corners.empty());
}

TEST(CornerExtractionTest, BlockedTablesAgreeWithTheDenseTable) {
  const Scene room = LRoom();
  CornerExtractionParams small;
  small.max_table_bytes = 4 * 24 * 24 * 24;  // blocks of 24 - 2 * 4 - 1 = 15 voxels
  const CornerExtractionResult dense = Extract(room);
  const CornerExtractionResult blocked = Extract(room, small);
  EXPECT_EQ(dense.table_blocks, 1u);
  EXPECT_GT(blocked.table_blocks, 1u);
  EXPECT_EQ(blocked.candidates, dense.candidates);
  EXPECT_EQ(blocked.corners.size(), dense.corners.size());
}

TEST(CornerExtractionTest, RefusesBadParamsAndTinyTables) {
  const VoxelGrid grid = Grid(AxisAlignedBox(VoxelKey(10, 10, 10), VoxelKey(0, 0, 0)));
  CornerExtractionParams params;
  params.window_size = 6;
  EXPECT_EQ(ExtractCorners(grid, params).status().code(), StatusCode::kInvalidArgument);
  params = {};
  params.plane_epsilon = std::nan("");
  EXPECT_EQ(ExtractCorners(grid, params).status().code(), StatusCode::kInvalidArgument);
  params = {};
  params.max_table_bytes = 100;
  EXPECT_EQ(ExtractCorners(grid, params).status().code(), StatusCode::kResourceExhausted);
  params = {};
  params.max_occupied_voxels = 10;
  EXPECT_EQ(ExtractCorners(grid, params).status().code(), StatusCode::kResourceExhausted);
}

}  // namespace
}  // namespace mapd::voxel
