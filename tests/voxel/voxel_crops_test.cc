// The crop generator of the real-map merge benchmark (tests/bench/voxel_crops.h)
// on a small generated corridor: overlap as defined, the ground truth maps B's
// voxels back onto the map, determinism.
#include "bench/voxel_crops.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>

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
  p.disjoint = true;  // a negative pair has no overlap to check
  EXPECT_TRUE(p.Validate().ok());
  p.gap_m = -1;
  EXPECT_NE(p.Validate().message().find("gap_m"), std::string::npos);
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

// The free voxels of `map` whose key along `axis` lies in [lo, hi].
std::size_t FreeInSlab(const voxel::VoxelGrid& map, int axis, int lo, int hi) {
  std::size_t n = 0;
  map.ForEachFreeCube([&](const voxel::VoxelKey& min_key, int edge) {
    for (int i = 0; i < edge; ++i) {
      const int k = min_key[axis] + i;
      if (k >= lo && k <= hi) n += static_cast<std::size_t>(edge) * edge;
    }
  });
  return n;
}

StatusOr<voxel::VoxelGrid> GridOf(const std::string& bt) {
  StatusOr<voxel::OcTreePtr> tree = voxel::ReadOctree(bt);
  if (!tree.ok()) return tree.status();
  return voxel::VoxelGrid::FromOcTree(**tree);
}

// A real submap keeps its ray-cast free space: crop A (the identity) carries
// every free voxel of the map inside its slab, including the corridor's
// interior far from any wall, and B the same number up to resampling.
TEST(VoxelCropsTest, CropsCarryAllFreeSpaceOfTheirSlab) {
  const voxel::VoxelGrid map = Corridor();
  CropParams p;
  p.overlap = 0.5;
  p.seed = 3;
  StatusOr<CropPair> pair = MakeCropPair(map, p);
  ASSERT_TRUE(pair.ok()) << pair.status().ToString();
  StatusOr<voxel::VoxelGrid> a = GridOf(pair->a_bt);
  ASSERT_TRUE(a.ok()) << a.status().ToString();
  const int lo = a->min_key()[pair->axis], hi = a->max_key()[pair->axis];
  const std::size_t expected = FreeInSlab(map, pair->axis, lo, hi);
  EXPECT_GT(expected, 10'000u);
  EXPECT_EQ(pair->out_free_a, expected);
  EXPECT_EQ(FreeInSlab(*a, pair->axis, lo, hi), expected);
  // The corridor's centre line (8+ voxels from the walls) is free in A.
  EXPECT_EQ(a->State(voxel::VoxelKey((lo + hi) / 2, 15, 10)), voxel::VoxelState::kFree);
  // B: the free space of its own slab (found by moving B's occupied voxels
  // back), resampled under a rotation: nearest neighbour duplicates or drops
  // a few voxels.
  StatusOr<voxel::VoxelGrid> b = GridOf(pair->b_bt);
  ASSERT_TRUE(b.ok()) << b.status().ToString();
  int b_lo = 1 << 20, b_hi = -(1 << 20);
  for (const Eigen::Vector3d& c : b->occupied_centres()) {
    const int k = map.PointToKey(pair->T_a_b * c)[pair->axis];
    b_lo = std::min(b_lo, k);
    b_hi = std::max(b_hi, k);
  }
  const double expected_b = static_cast<double>(FreeInSlab(map, pair->axis, b_lo, b_hi));
  EXPECT_NEAR(static_cast<double>(pair->out_free_b), expected_b, 0.15 * expected_b);
}

TEST(VoxelCropsTest, DisjointCropsShareNothingAndKeepTheGap) {
  const voxel::VoxelGrid map = Corridor();
  CropParams p;
  p.disjoint = true;
  p.gap_m = 1.0;  // 10 voxels
  p.seed = 5;
  StatusOr<CropPair> pair = MakeCropPair(map, p);
  ASSERT_TRUE(pair.ok()) << pair.status().ToString();
  EXPECT_EQ(pair->shared, 0u);
  EXPECT_EQ(pair->achieved_overlap, 0.0);
  EXPECT_GT(pair->occupied_a, 1000u);
  EXPECT_GT(pair->occupied_b, 1000u);
  // B moved back by the ground truth lies beyond A's last layer plus the gap.
  StatusOr<voxel::VoxelGrid> a = GridOf(pair->a_bt), b = GridOf(pair->b_bt);
  ASSERT_TRUE(a.ok() && b.ok());
  int b_min = 1 << 20;
  for (const Eigen::Vector3d& c : b->occupied_centres()) {
    b_min = std::min(b_min, map.PointToKey(pair->T_a_b * c)[pair->axis]);
  }
  EXPECT_GE(b_min, a->max_key()[pair->axis] + 10);
  // A map too short for the gap is refused.
  p.gap_m = 30.0;
  EXPECT_EQ(MakeCropPair(map, p).status().code(), StatusCode::kFailedPrecondition);
}

TEST(VoxelCropsTest, RefusesATinyMap) {
  StatusOr<voxel::VoxelGrid> tiny = voxel::VoxelGrid::FromKeys(0.1, {voxel::VoxelKey(0, 0, 0)});
  ASSERT_TRUE(tiny.ok());
  EXPECT_EQ(MakeCropPair(*tiny, CropParams()).status().code(), StatusCode::kFailedPrecondition);
}

}  // namespace
}  // namespace mapd::bench
