// The crop generator of the real-map merge benchmark (tests/bench/voxel_crops.h)
// on a small generated corridor: overlap as defined, the ground truth maps B's
// voxels back onto the map, determinism.
#include "bench/voxel_crops.h"

#include <gtest/gtest.h>

#include <cmath>

#include "voxel/octree_reader.h"
#include "voxel/voxel_grid.h"

namespace mapd::bench {
namespace {

// A closed corridor 240 x 30 x 20 voxels (0.1 m) with a few pillars so that it
// is not symmetric; free inside.
voxel::VoxelGrid Corridor() {
  std::vector<voxel::VoxelKey> occupied, free;
  const int nx = 240, ny = 30, nz = 20;
  for (int x = 0; x < nx; ++x) {
    for (int y = 0; y < ny; ++y) {
      for (int z = 0; z < nz; ++z) {
        const bool wall = x == 0 || x == nx - 1 || y == 0 || y == ny - 1 || z == 0 || z == nz - 1;
        const bool pillar =
            (x % 37 == 5 && y >= 3 && y <= 5) || (x % 53 == 9 && y >= 20 && y <= 25);
        (wall || pillar ? occupied : free).emplace_back(x, y, z);
      }
    }
  }
  StatusOr<voxel::VoxelGrid> grid = voxel::VoxelGrid::FromKeys(0.1, occupied, free);
  EXPECT_TRUE(grid.ok());
  return std::move(grid).value();
}

TEST(VoxelCropsTest, ValidateNamesTheBadField) {
  CropParams p;
  p.overlap = 1.0;
  EXPECT_NE(p.Validate().message().find("overlap"), std::string::npos);
  p = CropParams();
  p.free_band_voxels = -1;
  EXPECT_NE(p.Validate().message().find("free_band_voxels"), std::string::npos);
  EXPECT_TRUE(CropParams().Validate().ok());
}

TEST(VoxelCropsTest, OverlapGroundTruthAndDeterminism) {
  const voxel::VoxelGrid map = Corridor();
  CropParams p;
  p.overlap = 0.5;
  p.seed = 7;
  StatusOr<CropPair> pair = MakeCropPair(map, p);
  ASSERT_TRUE(pair.ok()) << pair.status().ToString();
  EXPECT_EQ(pair->axis, 0);
  EXPECT_NEAR(pair->achieved_overlap, 0.5, 0.05);
  EXPECT_LE(std::abs(pair->roll_deg), 10.0);
  EXPECT_LE(std::abs(pair->pitch_deg), 10.0);
  EXPECT_LE(pair->translation_m, 20.0);
  // Crop A is resampled with the identity: exactly its source voxels.
  EXPECT_EQ(pair->out_occupied_a, pair->occupied_a);

  // B's occupied voxels, moved back by the ground truth, land on the map's
  // occupied voxels (nearest-neighbour resampling: within one voxel).
  StatusOr<voxel::OcTreePtr> tree_b = voxel::ReadOctree(pair->b_bt);
  ASSERT_TRUE(tree_b.ok()) << tree_b.status().ToString();
  StatusOr<voxel::VoxelGrid> b = voxel::VoxelGrid::FromOcTree(**tree_b);
  ASSERT_TRUE(b.ok());
  EXPECT_NEAR(static_cast<double>(b->num_occupied()), static_cast<double>(pair->occupied_b),
              0.1 * pair->occupied_b);
  std::size_t hits = 0;
  for (const Eigen::Vector3d& c : b->occupied_centres()) {
    const voxel::VoxelKey k = map.PointToKey(pair->T_a_b * c);
    bool near = false;
    for (int dx = -1; dx <= 1 && !near; ++dx) {
      for (int dy = -1; dy <= 1 && !near; ++dy) {
        for (int dz = -1; dz <= 1 && !near; ++dz) {
          near = map.IsOccupied(k + voxel::VoxelKey(dx, dy, dz));
        }
      }
    }
    hits += near;
  }
  EXPECT_GT(static_cast<double>(hits), 0.99 * b->num_occupied());
  // The truth is the identity on the metrics.
  EXPECT_NEAR(RotationErrorDeg(pair->T_a_b, pair->T_a_b), 0.0, 1e-6);
  EXPECT_NEAR(TranslationErrorAt(pair->T_a_b, pair->T_a_b, pair->centroid_b), 0.0, 1e-9);

  StatusOr<CropPair> again = MakeCropPair(map, p);
  ASSERT_TRUE(again.ok());
  EXPECT_EQ(again->b_bt, pair->b_bt);
  EXPECT_TRUE(again->T_a_b.isApprox(pair->T_a_b));
  p.seed = 8;
  StatusOr<CropPair> other = MakeCropPair(map, p);
  ASSERT_TRUE(other.ok());
  EXPECT_FALSE(other->T_a_b.isApprox(pair->T_a_b));
}

TEST(VoxelCropsTest, CropsAreCappedAndOverlapFollowsTheRequest) {
  const voxel::VoxelGrid map = Corridor();
  for (double f : {0.3, 0.7}) {
    CropParams p;
    p.overlap = f;
    p.max_occupied_per_crop = 5000;
    StatusOr<CropPair> pair = MakeCropPair(map, p);
    ASSERT_TRUE(pair.ok()) << pair.status().ToString();
    EXPECT_NEAR(pair->achieved_overlap, f, 0.05) << f;
    EXPECT_LT(pair->occupied_a, 5600u);
    EXPECT_LT(pair->occupied_b, 5600u);
  }
}

TEST(VoxelCropsTest, RefusesATinyMap) {
  StatusOr<voxel::VoxelGrid> tiny = voxel::VoxelGrid::FromKeys(0.1, {voxel::VoxelKey(0, 0, 0)});
  ASSERT_TRUE(tiny.ok());
  EXPECT_EQ(MakeCropPair(*tiny, CropParams()).status().code(), StatusCode::kFailedPrecondition);
}

}  // namespace
}  // namespace mapd::bench
