// NearestVoxelIndex against brute force at every reach, its hash fallback for
// huge sparse boxes, box limits and empty queries.
#include "voxel/nearest_voxel.h"

#include <gtest/gtest.h>

#include <random>
#include <vector>

namespace mapd::voxel {
namespace {

constexpr double kCellM = 0.1;

// The nearest point within max_m (and inside `within`, if given) by brute
// force, ties to the lower index.
int BruteNearest(const std::vector<Eigen::Vector3d>& points, const Eigen::Vector3d& q, double max_m,
                 double* squared_m2, const Eigen::AlignedBox3d* within = nullptr) {
  int best = -1;
  double best_d = max_m * max_m;
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (within != nullptr && !within->contains(points[i])) continue;
    const double d = (points[i] - q).squaredNorm();
    if (d < best_d || (d == best_d && best < 0)) {
      best_d = d;
      best = static_cast<int>(i);
    }
  }
  *squared_m2 = best_d;
  return best;
}

// Voxel centres of a few walls (one point per cell, as ICP's targets) plus
// loose points, several to a cell.
std::vector<Eigen::Vector3d> Scene(std::mt19937* rng) {
  std::vector<Eigen::Vector3d> points;
  for (int x = 0; x < 60; ++x) {
    for (int z = 0; z < 25; ++z) {
      points.push_back(Eigen::Vector3d(x + 0.5, 0.5, z + 0.5) * kCellM);   // wall y = 0
      points.push_back(Eigen::Vector3d(0.5, x + 0.5, z + 0.5) * kCellM);   // wall x = 0
      points.push_back(Eigen::Vector3d(x + 0.5, 40.5, z + 0.5) * kCellM);  // wall y = 40
    }
  }
  std::uniform_real_distribution<double> u(0.0, 6.0);
  for (int i = 0; i < 400; ++i) points.emplace_back(u(*rng), u(*rng), 0.4 * u(*rng));
  return points;
}

void ExpectSameAsBruteForce(const std::vector<Eigen::Vector3d>& points,
                            const std::vector<Eigen::Vector3d>& queries, double max_m,
                            bool expect_dense, const Eigen::AlignedBox3d* within = nullptr) {
  const NearestVoxelIndex index(points, kCellM);
  EXPECT_EQ(index.dense(), expect_dense);
  int found = 0, gaps = 0;
  for (const Eigen::Vector3d& q : queries) {
    double want_d = 0;
    const int want = BruteNearest(points, q, max_m, &want_d, within);
    float got_d = 0;
    const int got = index.Nearest(q, max_m, &got_d, within);
    if (want < 0) {
      EXPECT_EQ(got, -1) << q.transpose();
      continue;
    }
    ++found;
    // Ties go to the lower index in both; distinct points at equal distance
    // are rare but the answer must not depend on the scan order.
    EXPECT_EQ(got, want) << q.transpose() << " max " << max_m;
    EXPECT_FLOAT_EQ(got_d, static_cast<float>(want_d));
    // The bound on the other points (ICP keeps a pairing by it): every other
    // point that counts is at least that far, and the answer no farther.
    double others_m2 = -1;
    float again_d = 0;
    EXPECT_EQ(index.Nearest(q, max_m, &again_d, within, &others_m2), got);
    EXPECT_EQ(again_d, got_d);
    EXPECT_GE(others_m2, want_d);
    for (std::size_t i = 0; i < points.size(); ++i) {
      if (static_cast<int>(i) == want || (within != nullptr && !within->contains(points[i]))) {
        continue;
      }
      ASSERT_GE((points[i] - q).squaredNorm(), others_m2) << q.transpose() << " point " << i;
    }
    // ... and it is a gap, not a bound of zero: most queries could move.
    gaps += others_m2 > want_d * 1.1 ? 1 : 0;
  }
  EXPECT_GT(gaps, found / 2);
  // The test tests something: most queries lie within 0.3 m of a point (the
  // boxed test counts its own).
  if (within == nullptr) {
    EXPECT_GT(found, static_cast<int>(queries.size()) / (max_m < 0.3 ? 100 : 4));
  }
}

TEST(NearestVoxelIndexTest, MatchesBruteForceWithinEveryReach) {
  std::mt19937 rng(7);
  const std::vector<Eigen::Vector3d> points = Scene(&rng);
  std::uniform_real_distribution<double> u(-0.5, 6.5);
  std::vector<Eigen::Vector3d> queries;
  for (int i = 0; i < 3000; ++i) queries.emplace_back(u(rng), u(rng), 0.5 * u(rng));
  // Queries on the lattice itself: exact ties between neighbours.
  for (int i = 0; i < 200; ++i) queries.emplace_back(i % 60 * kCellM, 0.0, (i % 7) * kCellM);
  // Within the near bits' reach (3 cells), at it, and beyond it (no shortcut).
  for (const double max_m : {0.05, 0.3, 0.3 + 1e-12, 0.75}) {
    ExpectSameAsBruteForce(points, queries, max_m, /*expect_dense=*/true);
  }
}

TEST(NearestVoxelIndexTest, AHugeSparseBoxFallsBackToTheHashWithTheSameAnswers) {
  std::mt19937 rng(11);
  std::vector<Eigen::Vector3d> points = Scene(&rng);
  // A far point makes the box ~10^12 cells: no bits, the hash answers.
  points.push_back(Eigen::Vector3d(1e3, 1e3, 1e3));
  std::uniform_real_distribution<double> u(-0.5, 6.5);
  std::vector<Eigen::Vector3d> queries;
  for (int i = 0; i < 2000; ++i) queries.emplace_back(u(rng), u(rng), 0.5 * u(rng));
  queries.push_back(Eigen::Vector3d(1e3, 1e3, 1e3 + 0.05));
  for (const double max_m : {0.3, 0.75}) {
    ExpectSameAsBruteForce(points, queries, max_m, /*expect_dense=*/false);
  }
}

// Limited to a box, the index answers as brute force over the points inside
// it: queries just outside the box's faces have their nearest points
// outside, and must get the nearest inside or none (ICP's shared target,
// icp.h). With the bit set and with the hash.
TEST(NearestVoxelIndexTest, ABoxLimitsTheAnswerToThePointsInside) {
  for (const bool far_point : {false, true}) {
    SCOPED_TRACE(far_point ? "hash" : "bit set");
    std::mt19937 rng(5);
    std::vector<Eigen::Vector3d> points = Scene(&rng);
    if (far_point) points.push_back(Eigen::Vector3d(1e3, 1e3, 1e3));
    // Cuts the walls y = 0 and y = 40 cells across, at x 1.02 and 4.0 m and
    // z 0.31 m; leaves out the wall x = 0. The queries are around it.
    const Eigen::AlignedBox3d box(Eigen::Vector3d(1.02, -1.0, 0.31),
                                  Eigen::Vector3d(4.0, 4.5, 9.0));
    std::uniform_real_distribution<double> ux(0.5, 4.5), uy(-0.3, 4.4), uz(0.0, 1.5);
    std::vector<Eigen::Vector3d> queries;
    for (int i = 0; i < 3000; ++i) queries.emplace_back(ux(rng), uy(rng), uz(rng));
    // The test tests something: many queries find a point inside, and many
    // have their nearest point overall outside (of those, some find another
    // inside, some none).
    int inside = 0, cut_off = 0;
    for (const Eigen::Vector3d& q : queries) {
      double d = 0;
      inside += BruteNearest(points, q, 0.3, &d, &box) >= 0 ? 1 : 0;
      const int any = BruteNearest(points, q, 0.3, &d);
      cut_off += any >= 0 && !box.contains(points[static_cast<std::size_t>(any)]) ? 1 : 0;
    }
    EXPECT_GT(inside, 500);
    EXPECT_GT(cut_off, 300);
    for (const double max_m : {0.3, 0.75}) {
      ExpectSameAsBruteForce(points, queries, max_m, /*expect_dense=*/!far_point, &box);
    }
  }
}

TEST(NearestVoxelIndexTest, EmptyAndFarQueriesFindNothing) {
  const NearestVoxelIndex empty({}, kCellM);
  float d = 0;
  EXPECT_EQ(empty.Nearest(Eigen::Vector3d::Zero(), 0.3, &d), -1);
  EXPECT_FLOAT_EQ(d, 0.09F);

  const std::vector<Eigen::Vector3d> one = {Eigen::Vector3d(0.05, 0.05, 0.05)};
  const NearestVoxelIndex index(one, kCellM);
  EXPECT_EQ(index.Nearest(Eigen::Vector3d(5, 5, 5), 0.3, &d), -1);
  // Far outside the cell range (clamped cells), still no answer and no crash.
  EXPECT_EQ(index.Nearest(Eigen::Vector3d(1e12, -1e12, 0), 0.3, &d), -1);
  EXPECT_EQ(index.Nearest(Eigen::Vector3d(0.05, 0.05, 0.3), 0.3, &d), 0);
  EXPECT_NEAR(d, 0.0625, 1e-6);
}

}  // namespace
}  // namespace mapd::voxel
