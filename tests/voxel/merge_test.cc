// The merge pipeline end to end (MergeSubmaps on generated rooms: right or
// refused, never wrong; refusals and their messages), the spanning tree, and
// the acceptance gates' measures (overlap score, shared free space, restart
// spread).
#include "voxel/merge.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "voxel/merge_graph.h"
#include "voxel/merge_overlap.h"
#include "voxel/merge_pair.h"
#include "voxel/octree_reader.h"
#include "voxel/submap_features.h"
#include "voxel/support/corner_scene.h"
#include "voxel/support/hostile_bt.h"
#include "voxel/support/voxel_scene.h"
#include "voxel/voxel_grid.h"

namespace mapd::voxel {
namespace {

using testing::FurnishedRoom;
using testing::kRoomResolutionM;
using testing::Pose;
using testing::RasteriseSubmap;
using testing::RoomCropX;

// Submap A is in the scene frame; B in the frame T_scene_b.
struct Pair {
  std::string a, b;
};

// The crops x in [-0.5, a_x1) and [b_x0, 9.5) m of the room: by default
// they share 4.6 m of its 9.
Pair MakePair(const Eigen::Isometry3d& T_scene_b, double a_x1 = 6.8, double b_x0 = 2.2) {
  return {RasteriseSubmap(FurnishedRoom(), RoomCropX(-0.5, a_x1), Eigen::Isometry3d::Identity(),
                          kRoomResolutionM),
          RasteriseSubmap(FurnishedRoom(), RoomCropX(b_x0, 9.5), T_scene_b, kRoomResolutionM)};
}

void ExpectFusedMapCoversBoth(const MergeOutcome& outcome, const std::string& a_bytes) {
  auto merged = InspectSubmap(outcome.merged_bt);
  ASSERT_TRUE(merged.ok()) << merged.status().ToString();
  EXPECT_EQ(merged->resolution, kRoomResolutionM);
  EXPECT_EQ(merged->occupied_voxels, outcome.occupied_voxels);
  EXPECT_LT(merged->bounds_min.x(), 0.05);  // A's wall at x = 0.05 m
  EXPECT_GT(merged->bounds_max.x(), 8.9);   // B's far wall at x = 9.05 m, in A's frame
  const auto a = InspectSubmap(a_bytes);
  ASSERT_TRUE(a.ok());
  EXPECT_GT(merged->occupied_voxels, a->occupied_voxels);
}

// A pose in degrees and metres, so that test names and failures can say it.
struct PoseCase {
  const char* name;
  double yaw_deg, pitch_deg, roll_deg;
  double x_m, y_m, z_m;
};
void PrintTo(const PoseCase& p, std::ostream* out) {
  *out << "yaw " << p.yaw_deg << " pitch " << p.pitch_deg << " roll " << p.roll_deg << " deg, t ("
       << p.x_m << ", " << p.y_m << ", " << p.z_m << ") m";
}

class MergeKnownTransformTest : public ::testing::TestWithParam<PoseCase> {};

TEST_P(MergeKnownTransformTest, RecoversTheTransformAndFuses) {
  const PoseCase& p = GetParam();
  const Eigen::Isometry3d T_a_b =
      Pose(p.yaw_deg, p.pitch_deg, p.roll_deg, Eigen::Vector3d(p.x_m, p.y_m, p.z_m));
  const Pair pair = MakePair(T_a_b);
  // The default order (the correlation generator first, which places this
  // pair) and corner matching first (the paper's method alone would too).
  // Correlation first relies on the shared free space gate: without it two
  // of these poses were refused as ambiguous between placements that put
  // one room's floor on the other's ceiling (2.5 m up, support 0.18-0.26).
  for (const int after_corner_stages : {0, 1}) {
    SCOPED_TRACE(after_corner_stages == 0 ? "correlation first" : "corner matching first");
    MergeParams params;
    params.correlation.after_corner_stages = after_corner_stages;
    std::vector<std::pair<std::string, double>> progress;
    auto outcome =
        MergeSubmaps({{11, pair.a}, {12, pair.b}}, params,
                     [&](const std::string& stage, double f) { progress.emplace_back(stage, f); });
    ASSERT_TRUE(outcome.ok()) << outcome.status().ToString();
    ASSERT_EQ(outcome->alignments.size(), 2u);
    EXPECT_EQ(outcome->alignments[0].id, 11u);
    EXPECT_TRUE(outcome->alignments[0].T_reference_submap.isApprox(Eigen::Isometry3d::Identity()));
    const Alignment& b = outcome->alignments[1];
    EXPECT_EQ(b.id, 12u);
    EXPECT_LT(testing::RotationErrorDeg(b.T_reference_submap, T_a_b), 1.0);
    EXPECT_LT(testing::TranslationError(b.T_reference_submap, T_a_b), 2 * kRoomResolutionM);
    if (after_corner_stages > 0) {
      EXPECT_GE(b.matched_corners, 4);
      EXPECT_TRUE(b.by_corners) << b.source;  // its corners count in the second look
    }
    EXPECT_TRUE(
        CheckMergeEvidence(*outcome, {kRoomResolutionM, kRoomResolutionM}, MergeParams()).ok());
    EXPECT_GE(b.overlap_score, 0.9);
    EXPECT_LE(b.residual_m, kRoomResolutionM);
    ExpectFusedMapCoversBoth(*outcome, pair.a);

    ASSERT_FALSE(progress.empty());
    for (std::size_t i = 1; i < progress.size(); ++i)
      EXPECT_GE(progress[i].second, progress[i - 1].second);
    EXPECT_EQ(progress.back().first, "fusion");
    EXPECT_EQ(progress.back().second, 1.0);
    EXPECT_GT(outcome->times.total_s, 0.0);
  }
}

std::string PoseCaseName(const ::testing::TestParamInfo<PoseCase>& param) {
  return param.param.name;
}

// Poses (yaw, pitch, roll up to 10 deg) where corner matching finds the true
// clique on this scene.
INSTANTIATE_TEST_SUITE_P(
    Poses, MergeKnownTransformTest,
    ::testing::Values(PoseCase{"identity", 0, 0, 0, 0, 0, 0},
                      PoseCase{"yaw37_pitch4_rollm6", 37, 4, -6, 1.3, -2.1, 0.4},
                      PoseCase{"yawm128_pitchm10_roll8", -128, -10, 8, -4.0, 3.3, -0.7}),
    PoseCaseName);

// The room is nearly symmetric under a half turn, and placements that flip
// it, or that stand one crop on the other's ceiling, put walls on walls.
// Whatever the generators propose, a merge must be either right or refused:
// a wrong merge is worse than none (docs/algorithms.md B.5). The usual crops
// (4.6 m shared) merge right in every pose, in either generator order. Crops
// that share a 0.7 m strip do not: the best placement found is B turned by
// a half turn from the truth and lifted onto A's ceiling (residual 0.35
// voxels, overlap 1.00), and the pair is refused.
TEST(MergeTest, NeverAcceptsAWrongTransform) {
  struct Case {
    const char* name;
    Eigen::Isometry3d T_a_b;
    double a_x1, b_x0;  // the crops: x in [-0.5, a_x1) and [b_x0, 9.5) m
    bool refused;       // else right
  };
  const Case cases[] = {
      {"half turn, far", Pose(172, 9, 10, Eigen::Vector3d(12.0, 0.5, 2.0)), 6.8, 2.2, false},
      {"half turn, near", Pose(172, 9, 10, Eigen::Vector3d(-4.0, 3.3, -0.7)), 6.8, 2.2, false},
      {"yaw 64", Pose(64, 3, -5, Eigen::Vector3d(2.0, 1.0, 0.3)), 6.8, 2.2, false},
      {"yaw -97", Pose(-97, -7, 2, Eigen::Vector3d(-1.5, 6.0, -0.2)), 6.8, 2.2, false},
      {"yaw 90", Pose(90, 0, 0, Eigen::Vector3d(0.3, 0.2, 0.1)), 6.8, 2.2, false},
      {"half turn, 0.7 m strip", Pose(178, 2, -3, Eigen::Vector3d(1.0, 0.5, 0.2)), 4.5, 3.8, true},
  };
  for (const Case& c : cases) {
    const Pair pair = MakePair(c.T_a_b, c.a_x1, c.b_x0);
    for (const int after_corner_stages : {0, 1}) {
      SCOPED_TRACE(std::string(c.name) +
                   (after_corner_stages == 0 ? ", correlation first" : ", corner matching first"));
      MergeParams params;
      params.correlation.after_corner_stages = after_corner_stages;
      auto outcome = MergeSubmaps({{1, pair.a}, {2, pair.b}}, params);
      if (c.refused) {
        ASSERT_FALSE(outcome.ok())
            << "merged " << outcome->pairs.front().source << ", "
            << testing::RotationErrorDeg(outcome->alignments[1].T_reference_submap, c.T_a_b)
            << " deg off";
        EXPECT_EQ(outcome.status().code(), StatusCode::kFailedPrecondition);
        // The best placement's refusal: the space in front of its walls.
        EXPECT_NE(outcome.status().message().find("refused: shared free space 0.00"),
                  std::string::npos)
            << outcome.status().message();
        continue;
      }
      ASSERT_TRUE(outcome.ok()) << outcome.status().ToString();
      EXPECT_LT(testing::RotationErrorDeg(outcome->alignments[1].T_reference_submap, c.T_a_b), 1.0);
      EXPECT_LT(testing::TranslationError(outcome->alignments[1].T_reference_submap, c.T_a_b),
                2 * kRoomResolutionM);
    }
  }

  // The strip pair is refused by the gates, not for want of a placement:
  // without the shared free space gate its wrong placements pass every other
  // one and only the uniqueness gate, which finds two of them, refuses it;
  // without that too it merges wrong.
  const Case& strip = cases[5];
  const Pair pair = MakePair(strip.T_a_b, strip.a_x1, strip.b_x0);
  MergeParams params;
  params.min_shared_free_ratio = 0;
  auto ambiguous = MergeSubmaps({{1, pair.a}, {2, pair.b}}, params);
  ASSERT_FALSE(ambiguous.ok()) << "merged " << ambiguous->pairs.front().source;
  EXPECT_NE(ambiguous.status().message().find("ambiguous: two distinct alignments pass every gate"),
            std::string::npos)
      << ambiguous.status().message();
  params.ambiguous_support_ratio = 1;  // a rival only with the most support, a tie
  params.ambiguous_overlap_margin = 1;
  auto wrong = MergeSubmaps({{1, pair.a}, {2, pair.b}}, params);
  ASSERT_TRUE(wrong.ok()) << wrong.status().ToString();
  EXPECT_GT(testing::RotationErrorDeg(wrong->alignments[1].T_reference_submap, strip.T_a_b), 90.0);
}

// Three submaps, every pair overlapping: the spanning tree places all three.
// (A true chain, with the first and the last not overlapping, is covered on
// synthetic edges by MergeGraphTest: on cuts of this room with smaller
// overlaps the corner matcher returned wrong cliques, which were refused.)
TEST(MergeTest, PlacesThreeSubmapsInTheFirstFrame) {
  const Eigen::Isometry3d T_scene_b = Pose(37, 4, -6, Eigen::Vector3d(1.3, -2.1, 0.4));
  const Eigen::Isometry3d T_scene_c = Pose(-128, -10, 8, Eigen::Vector3d(-4.0, 3.3, -0.7));
  const std::string a = RasteriseSubmap(FurnishedRoom(), RoomCropX(-0.5, 6.8),
                                        Eigen::Isometry3d::Identity(), kRoomResolutionM);
  const std::string b =
      RasteriseSubmap(FurnishedRoom(), RoomCropX(2.2, 9.5), T_scene_b, kRoomResolutionM);
  const std::string c =
      RasteriseSubmap(FurnishedRoom(), RoomCropX(2.2, 9.5), T_scene_c, kRoomResolutionM);
  auto outcome = MergeSubmaps({{1, a}, {2, b}, {3, c}}, MergeParams{});
  ASSERT_TRUE(outcome.ok()) << outcome.status().ToString();
  ASSERT_EQ(outcome->alignments.size(), 3u);
  EXPECT_EQ(outcome->pairs.size(), 3u);
  EXPECT_LT(testing::RotationErrorDeg(outcome->alignments[1].T_reference_submap, T_scene_b), 1.0);
  EXPECT_LT(testing::TranslationError(outcome->alignments[1].T_reference_submap, T_scene_b),
            2 * kRoomResolutionM);
  EXPECT_LT(testing::RotationErrorDeg(outcome->alignments[2].T_reference_submap, T_scene_c), 1.0);
  EXPECT_LT(testing::TranslationError(outcome->alignments[2].T_reference_submap, T_scene_c),
            2 * kRoomResolutionM);
  ExpectFusedMapCoversBoth(*outcome, a);
}

// A chain 0 - 1 - 2 (no edge 0 - 2) and a weaker cycle edge: the tree keeps
// the strong edges and composes the transforms along them.
TEST(MergeGraphTest, PlacesAChainAndLeavesTheUnconnectedOut) {
  const Eigen::Isometry3d T01 = Pose(30, 0, 0, Eigen::Vector3d(1, 0, 0));
  const Eigen::Isometry3d T12 = Pose(-70, 5, 0, Eigen::Vector3d(0, 2, 0));
  const Eigen::Isometry3d T_wrong = Pose(10, 0, 0, Eigen::Vector3d(9, 9, 9));
  // Edge 2 -> 1 given the other way round (a = 2, b = 1).
  const std::vector<MergeEdge> edges = {
      {0, 1, T01, 8.5}, {2, 1, T12.inverse(), 7.9}, {0, 2, T_wrong, 4.2}};
  const TreePlacement placement = PlaceAlongMaximumSpanningTree(4, edges, 0);
  EXPECT_TRUE(placement.placed[0] && placement.placed[1] && placement.placed[2]);
  EXPECT_FALSE(placement.placed[3]);
  EXPECT_TRUE(placement.T_root_node[1].isApprox(T01, 1e-12));
  EXPECT_TRUE(placement.T_root_node[2].isApprox(T01 * T12, 1e-12));
  EXPECT_EQ(placement.parent[2], 1);
  EXPECT_EQ(placement.order, (std::vector<int>{0, 1, 2}));
}

TEST(MergeTest, RefusesAMapWithoutCorners) {
  const std::string room = RasteriseSubmap(FurnishedRoom(), RoomCropX(-0.5, 5.6),
                                           Eigen::Isometry3d::Identity(), kRoomResolutionM);
  const std::string wall = RasteriseSubmap(
      testing::FlatWall(), Eigen::AlignedBox3d(Eigen::Vector3d(0, -1, 0), Eigen::Vector3d(6, 1, 3)),
      Eigen::Isometry3d::Identity(), kRoomResolutionM);
  MergeParams corners_only;
  corners_only.correlation.enabled = false;
  auto outcome = MergeSubmaps({{1, room}, {7, wall}}, corners_only);
  ASSERT_FALSE(outcome.ok());
  EXPECT_EQ(outcome.status().code(), StatusCode::kFailedPrecondition);
  EXPECT_EQ(outcome.status().message(), "no corners found in submap 7");
  // With the correlation generator, every stage says why.
  outcome = MergeSubmaps({{1, room}, {7, wall}}, MergeParams{});
  ASSERT_FALSE(outcome.ok());
  EXPECT_EQ(outcome.status().code(), StatusCode::kFailedPrecondition);
  EXPECT_NE(outcome.status().message().find("only 0 corners found in submap 7"), std::string::npos)
      << outcome.status().message();
  EXPECT_NE(outcome.status().message().find("correlation: not run (submap 7: no floor"),
            std::string::npos)
      << outcome.status().message();
}

TEST(MergeTest, RefusesMapsThatDoNotOverlap) {
  const std::string room = RasteriseSubmap(FurnishedRoom(), RoomCropX(-0.5, 5.6),
                                           Eigen::Isometry3d::Identity(), kRoomResolutionM);
  const std::string other =
      RasteriseSubmap(testing::OtherRoom(),
                      Eigen::AlignedBox3d(Eigen::Vector3d(19, 19, -1), Eigen::Vector3d(28, 27, 4)),
                      Pose(30, 0, 0, Eigen::Vector3d(-20, -10, 0)), kRoomResolutionM);
  auto outcome = MergeSubmaps({{1, room}, {2, other}}, MergeParams{});
  ASSERT_FALSE(outcome.ok());
  EXPECT_EQ(outcome.status().code(), StatusCode::kFailedPrecondition);
  EXPECT_NE(outcome.status().message().find("submap 1 and submap 2 not merged: "),
            std::string::npos)
      << outcome.status().message();
}

TEST(MergeTest, RefusalsNameTheFigureAndTheThreshold) {
  const Pair pair = MakePair(Pose(37, 4, -6, Eigen::Vector3d(1.3, -2.1, 0.4)));
  MergeParams params;
  params.min_matched_corners = 1000;
  params.correlation.enabled = false;  // corners only: the up-front corner count
  auto outcome = MergeSubmaps({{1, pair.a}, {2, pair.b}}, params);
  ASSERT_FALSE(outcome.ok());
  EXPECT_EQ(outcome.status().code(), StatusCode::kFailedPrecondition);
  EXPECT_NE(outcome.status().message().find("corners found in submap 1, need 1000"),
            std::string::npos)
      << outcome.status().message();

  params = MergeParams{};
  params.max_residual_voxels = 0.01;  // voxel centres of rotated grids are never that close
  outcome = MergeSubmaps({{1, pair.a}, {2, pair.b}}, params);
  ASSERT_FALSE(outcome.ok());
  EXPECT_EQ(outcome.status().code(), StatusCode::kFailedPrecondition);
  EXPECT_NE(outcome.status().message().find("voxels) above 0.01 voxels"), std::string::npos)
      << outcome.status().message();

  // An ICP still moving when its iterations run out is not accepted, however
  // small its residual.
  params = MergeParams{};
  params.icp.max_iterations = 1;
  params.max_residual_voxels = 1000;
  outcome = MergeSubmaps({{1, pair.a}, {2, pair.b}}, params);
  ASSERT_FALSE(outcome.ok());
  EXPECT_EQ(outcome.status().code(), StatusCode::kFailedPrecondition);
  EXPECT_NE(outcome.status().message().find("ICP did not converge in 1 iterations"),
            std::string::npos)
      << outcome.status().message();
}

TEST(MergeTest, RefusesMismatchedResolutionsUnderRefuse) {
  const std::string a = RasteriseSubmap(FurnishedRoom(), RoomCropX(-0.5, 5.6),
                                        Eigen::Isometry3d::Identity(), kRoomResolutionM);
  const std::string b =
      RasteriseSubmap(FurnishedRoom(), RoomCropX(2.2, 9.5), Eigen::Isometry3d::Identity(), 0.2);
  auto outcome = MergeSubmaps({{1, a}, {2, b}}, MergeParams{});
  ASSERT_FALSE(outcome.ok());
  EXPECT_EQ(outcome.status().code(), StatusCode::kFailedPrecondition);
  // Names the service's setting and its values: what the operator can change.
  EXPECT_EQ(outcome.status().message(),
            "submap 1 has resolution 0.1 m, submap 2 has 0.2 m; merge.resolution_policy is refuse "
            "(allowed: refuse, resample); set it to resample to merge them at the finest "
            "resolution");
}

// Part 5 of issue 14: the residual gate is in voxels of the COARSER map. A
// right merge of a coarse (0.1 m) and a fine (0.05 m) rasterisation of one
// room ends near half a coarse voxel (0.043 m: 0.43 coarse, 0.87 fine voxels),
// above the 0.75 gate in fine voxels: the former finer-map unit refused it.
// Resampled to the finest, it must be accepted.
TEST(MergeTest, AcceptsARightCrossResolutionMergeUnderResample) {
  constexpr double kFine = 0.05, kCoarse = 0.1;
  const Eigen::Isometry3d T_a_b = Pose(35.0, 2.0, -1.0, Eigen::Vector3d(0.7, -0.4, 0.1));
  const std::string a = RasteriseSubmap(FurnishedRoom(), RoomCropX(-0.5, 6.8),
                                        Eigen::Isometry3d::Identity(), kCoarse);
  const std::string b = RasteriseSubmap(FurnishedRoom(), RoomCropX(2.2, 9.5), T_a_b, kFine);
  MergeParams params;
  params.resolution_policy = ResolutionPolicy::kResampleToFinest;
  auto outcome = MergeSubmaps({{1, a}, {2, b}}, params);
  ASSERT_TRUE(outcome.ok()) << outcome.status().ToString();
  EXPECT_EQ(outcome->resolution, kFine);
  const Alignment& placed = outcome->alignments[1];
  EXPECT_LT(testing::RotationErrorDeg(placed.T_reference_submap, T_a_b), 1.0);
  EXPECT_LT(testing::TranslationError(placed.T_reference_submap, T_a_b), 2 * kFine);
  // Within the gate in coarse voxels, above it in fine ones (the old unit).
  EXPECT_LE(placed.residual_m / kCoarse, params.max_residual_voxels);
  EXPECT_GT(placed.residual_m / kFine, params.max_residual_voxels);

  // A residual refusal of such a pair says which voxel it counts in.
  params.max_residual_voxels = 0.2;
  outcome = MergeSubmaps({{1, a}, {2, b}}, params);
  ASSERT_FALSE(outcome.ok());
  EXPECT_NE(outcome.status().message().find("voxels of the coarser map, 0.100 m"),
            std::string::npos)
      << outcome.status().message();

  // Under refuse, the same pair is refused before any work, naming the setting.
  params.resolution_policy = ResolutionPolicy::kRefuse;
  outcome = MergeSubmaps({{1, a}, {2, b}}, params);
  ASSERT_FALSE(outcome.ok());
  EXPECT_EQ(outcome.status().code(), StatusCode::kFailedPrecondition);
  EXPECT_NE(outcome.status().message().find("merge.resolution_policy"), std::string::npos)
      << outcome.status().message();
}

// The same pair with the coarse map second. Corner matching refuses this
// order (measuring D in coarser voxels did not change that); the
// correlation generator places it, within the same tolerances.
TEST(MergeTest, AcceptsARightCrossResolutionMergeWithTheCoarseMapSecond) {
  constexpr double kFine = 0.05, kCoarse = 0.1;
  const Eigen::Isometry3d T_a_b = Pose(35.0, 2.0, -1.0, Eigen::Vector3d(0.7, -0.4, 0.1));
  const std::string a =
      RasteriseSubmap(FurnishedRoom(), RoomCropX(-0.5, 6.8), Eigen::Isometry3d::Identity(), kFine);
  const std::string b = RasteriseSubmap(FurnishedRoom(), RoomCropX(2.2, 9.5), T_a_b, kCoarse);
  MergeParams params;
  params.resolution_policy = ResolutionPolicy::kResampleToFinest;
  auto outcome = MergeSubmaps({{1, a}, {2, b}}, params);
  ASSERT_TRUE(outcome.ok()) << outcome.status().ToString();
  const Alignment& placed = outcome->alignments[1];
  EXPECT_LT(testing::RotationErrorDeg(placed.T_reference_submap, T_a_b), 1.0);
  EXPECT_LT(testing::TranslationError(placed.T_reference_submap, T_a_b), 2 * kFine);
}

TEST(MergeTest, RefusesMalformedInputAndFewerThanTwoMaps) {
  const std::string a = RasteriseSubmap(FurnishedRoom(), RoomCropX(-0.5, 5.6),
                                        Eigen::Isometry3d::Identity(), kRoomResolutionM);
  auto outcome = MergeSubmaps({{1, a}, {9, "# Octomap OcTree binary file\nid OcTree\nsize 3\n"}},
                              MergeParams{});
  ASSERT_FALSE(outcome.ok());
  EXPECT_EQ(outcome.status().code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(outcome.status().message().rfind("submap 9: ", 0), 0u) << outcome.status().message();

  outcome = MergeSubmaps({{1, a}}, MergeParams{});
  ASSERT_FALSE(outcome.ok());
  EXPECT_EQ(outcome.status().code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(outcome.status().message(), "a merge needs at least two submaps, got 1");

  outcome = MergeSubmaps({{1, a}, {1, a}}, MergeParams{});
  ASSERT_FALSE(outcome.ok());
  EXPECT_EQ(outcome.status().message(), "submap 1 is given twice");
}

TEST(MergeTest, ValidateNamesTheBadField) {
  MergeParams params;
  params.min_matched_corners = 2;
  EXPECT_NE(params.Validate().message().find("min_matched_corners"), std::string::npos);
  params = MergeParams{};
  params.min_overlap_score = 1.5;
  EXPECT_NE(params.Validate().message().find("min_overlap_score"), std::string::npos);
  for (const double bad : {-1.0, std::nan(""), std::numeric_limits<double>::infinity()}) {
    params = MergeParams{};
    params.min_shared_free_ratio = bad;
    EXPECT_NE(params.Validate().message().find("min_shared_free_ratio"), std::string::npos);
    params = MergeParams{};
    params.max_restart_spread_voxels = bad;
    EXPECT_NE(params.Validate().message().find("max_restart_spread_voxels"), std::string::npos);
    params = MergeParams{};
    params.restart_turn_deg = bad;
    EXPECT_NE(params.Validate().message().find("restart_turn_deg"), std::string::npos);
  }
  params = MergeParams{};
  params.icp.trim_fraction = 0.0;
  EXPECT_NE(params.Validate().message().find("icp.trim_fraction"), std::string::npos);
  params = MergeParams{};
  params.max_seconds = -1;
  EXPECT_NE(params.Validate().message().find("max_seconds"), std::string::npos);
  params = MergeParams{};
  params.looser_tolerances = {{25.0, 15.0}, {-1.0, 30.0}};
  EXPECT_NE(params.Validate().message().find("looser_tolerances[1]"), std::string::npos);
  params = MergeParams{};
  params.icp_screen_residual_factor = 0.5;
  EXPECT_NE(params.Validate().message().find("icp_screen_residual_factor"), std::string::npos);
  params = MergeParams{};
  params.matching.max_candidate_pairs = -5;
  EXPECT_NE(params.Validate().message().find("max_candidate_pairs must be >= 0"),
            std::string::npos);
  EXPECT_TRUE(MergeParams{}.Validate().ok());
}

TEST(MergeTest, StopsWhenTheTimeBudgetIsSpent) {
  const Pair pair = MakePair(Eigen::Isometry3d::Identity());
  MergeParams params;
  params.max_seconds = 1e-9;
  // The message names the stage that ran out: the first one, whichever it is.
  for (const auto& [after_corner_stages, stage] :
       {std::pair<int, const char*>{0, "during matching and alignment"},
        std::pair<int, const char*>{1, "during corner extraction"}}) {
    params.correlation.after_corner_stages = after_corner_stages;
    auto outcome = MergeSubmaps({{1, pair.a}, {2, pair.b}}, params);
    ASSERT_FALSE(outcome.ok());
    EXPECT_EQ(outcome.status().code(), StatusCode::kResourceExhausted);
    EXPECT_NE(outcome.status().message().find(stage), std::string::npos)
        << outcome.status().message();
  }
}

// The definition in merge.h, voxel by voxel.
TEST(OverlapScoreTest, CountsCoincidingAmongObservedVoxels) {
  std::vector<VoxelKey> a_occupied, a_free;
  for (int x = 0; x < 10; ++x) {
    a_occupied.emplace_back(x, 0, 0);  // a wall along x
    for (int y = 1; y <= 3; ++y) a_free.emplace_back(x, y, 0);
  }
  const std::vector<VoxelKey> b_occupied = {
      {0, 0, 0},  {1, 0, 0},  {2, 0, 0}, {3, 0, 0},  // on A's wall
      {5, 1, 0},                                     // next to it: one voxel of tolerance
      {0, 3, 0},  {1, 3, 0},                         // in A's free space
      {50, 0, 0}, {51, 0, 0}, {52, 0, 0}};           // in A's unknown space: not counted
  auto a = VoxelGrid::FromKeys(kRoomResolutionM, a_occupied, a_free);
  auto b = VoxelGrid::FromKeys(kRoomResolutionM, b_occupied);
  ASSERT_TRUE(a.ok() && b.ok());
  const OverlapScore score = ComputeOverlapScore(*a, *b, Eigen::Isometry3d::Identity());
  EXPECT_EQ(score.observed, 7u);
  EXPECT_EQ(score.coinciding, 5u);
  EXPECT_DOUBLE_EQ(score.score, 5.0 / 7.0);
  // Moved 3 voxels along y, B's wall lies in A's free space.
  const OverlapScore moved = ComputeOverlapScore(
      *a, *b, Eigen::Isometry3d(Eigen::Translation3d(0.0, 3 * kRoomResolutionM, 0.0)));
  EXPECT_LT(moved.score, 0.2);
}

// Two overlapping crops of the furnished room with their free space, in the
// scene frame: x in [-0.5, 5.6) m and [2.0, 8.0) m.
void OverlappingRoomGrids(VoxelGrid* a, VoxelGrid* b) {
  const auto crop = [](double x_min_m, double x_max_m, VoxelGrid* out) {
    auto tree = ReadOctree(RasteriseSubmap(FurnishedRoom(), RoomCropX(x_min_m, x_max_m),
                                           Eigen::Isometry3d::Identity(), kRoomResolutionM));
    ASSERT_TRUE(tree.ok()) << tree.status().ToString();
    auto grid = VoxelGrid::FromOcTree(**tree);
    ASSERT_TRUE(grid.ok()) << grid.status().ToString();
    *out = std::move(*grid);
  };
  crop(-0.5, 5.6, a);
  crop(2.0, 8.0, b);
}

TEST(OverlapScoreTest, TheIndexGivesTheGridsCounts) {
  // A furnished room with its free space against a moved crop of it; and the
  // wall above, whose free space lies outside the occupied box (grid path).
  VoxelGrid a, b;
  ASSERT_NO_FATAL_FAILURE(OverlappingRoomGrids(&a, &b));
  std::vector<VoxelKey> wall, free;
  for (int x = 0; x < 10; ++x) {
    wall.emplace_back(x, 0, 0);
    for (int y = 1; y <= 6; ++y) free.emplace_back(x, y, 0);
  }
  auto wall_grid = VoxelGrid::FromKeys(kRoomResolutionM, wall, free);
  ASSERT_TRUE(wall_grid.ok());
  for (const VoxelGrid* grid : {&a, &*wall_grid}) {
    const OverlapIndex bits(*grid);
    const OverlapIndex no_bits(*grid, /*max_cells=*/1);
    // Room for the occupied box (grown by one) only: free space beyond it
    // is the grid's to answer.
    const VoxelKey box = grid->max_key() - grid->min_key() + VoxelKey::Constant(3);
    const OverlapIndex occupied_box(*grid, static_cast<std::size_t>(box.prod()));
    ASSERT_TRUE(bits.has_bits() && bits.observes_everywhere());
    ASSERT_FALSE(no_bits.has_bits());
    ASSERT_TRUE(occupied_box.has_bits());
    // The wall's free space lies beyond its occupied box.
    if (grid == &*wall_grid) {
      ASSERT_FALSE(occupied_box.observes_everywhere());
    }
    for (const Eigen::Isometry3d& T :
         {Eigen::Isometry3d::Identity(), Pose(0, 0, 0, Eigen::Vector3d(0.0, 0.35, 0.0)),
          Pose(17, 2, -3, Eigen::Vector3d(0.4, -0.3, 0.1)),
          Pose(90, 0, 0, Eigen::Vector3d(3.0, 1.0, 0.0))}) {
      const OverlapScore want = ComputeOverlapScore(*grid, b, T);
      for (const OverlapIndex* index : {&bits, &no_bits, &occupied_box}) {
        const OverlapScore got = ComputeOverlapScore(*index, b, T);
        EXPECT_EQ(got.observed, want.observed);
        EXPECT_EQ(got.coinciding, want.coinciding);
      }
    }
  }
}

// The touching-placement gate. B is A turned 180 deg about a
// vertical axis in A's end wall: that wall lands on itself and the rest of B
// in A's unknown space beyond it, so overlap and support pass, but no free
// voxel of B lands on A's free space. A right placement of an overlapping
// crop shares the room between them.
TEST(SharedFreeGateTest, RefusesAPlacementThatSharesOnlyAWall) {
  VoxelGrid a, b;
  ASSERT_NO_FATAL_FAILURE(OverlappingRoomGrids(&a, &b));
  ASSERT_TRUE(a.has_free_space() && b.has_free_space());
  const OverlapIndex index(a);
  const auto ratio = [](const SharedFree& free, const OverlapScore& overlap) {
    return free.shared_voxels() / static_cast<double>(overlap.coinciding);
  };

  const Eigen::Isometry3d right = Eigen::Isometry3d::Identity();
  const SharedFree shared = ComputeSharedFree(index, b, right, 0);
  const OverlapScore overlap = ComputeOverlapScore(index, b, right);
  EXPECT_EQ(shared.stride, 1);
  EXPECT_GT(ratio(shared, overlap), 2.0);
  // A sparser lattice estimates the same volume.
  const SharedFree sampled = ComputeSharedFree(index, b, right, shared.evaluated / 8);
  EXPECT_GE(sampled.stride, 2);
  EXPECT_NEAR(sampled.shared_voxels(), shared.shared_voxels(), 0.1 * shared.shared_voxels());

  // The turn about A's wall at x = min_key.x: voxel centres land on centres.
  const double res = a.resolution();
  const Eigen::Vector3d axis((a.min_key().x() + 0.5) * res,
                             (a.min_key().y() + a.max_key().y() + 1) * 0.5 * res, 0.0);
  const Eigen::Isometry3d touching = Eigen::Translation3d(axis) *
                                     Eigen::AngleAxisd(M_PI, Eigen::Vector3d::UnitZ()) *
                                     Eigen::Translation3d(-axis);
  const OverlapScore touching_overlap = ComputeOverlapScore(index, a, touching);
  ASSERT_GT(touching_overlap.observed, 0u);
  EXPECT_GE(touching_overlap.score, MergeParams{}.min_overlap_score);
  EXPECT_GE(static_cast<double>(touching_overlap.coinciding) / a.num_occupied(),
            MergeParams{}.min_support_fraction);
  const SharedFree touching_free = ComputeSharedFree(index, a, touching, 0);
  EXPECT_GT(touching_free.evaluated, 0u);
  EXPECT_EQ(touching_free.shared, 0u);

  // Through ICP and every gate (RefineAndGate): the touching placement passes
  // residual, overlap and support, and only the shared free space refuses it.
  MergeParams params;
  SubmapFeatures features_a(1, &a, &params), features_b(2, &b, &params),
      features_a_as_b(2, &a, &params);
  const PairSide side_a{1, &a, &features_a};
  StageTimes times;
  PairReport touching_report;
  ASSERT_TRUE(RefineAndGate(side_a, {2, &a, &features_a_as_b}, params, touching, res, &times,
                            &touching_report)
                  .ok());
  EXPECT_FALSE(touching_report.accepted);
  EXPECT_NE(touching_report.reason.find("shared free space 0.00"), std::string::npos)
      << touching_report.reason;
  EXPECT_GE(touching_report.overlap_score, params.min_overlap_score);
  EXPECT_GE(touching_report.support_fraction, params.min_support_fraction);
  PairReport right_report;
  ASSERT_TRUE(
      RefineAndGate(side_a, {2, &b, &features_b}, params, right, res, &times, &right_report).ok());
  EXPECT_TRUE(right_report.accepted) << right_report.reason;
  EXPECT_GT(right_report.shared_free_ratio, 2.0);
  // Off, the gate lets the touching placement through: nothing else stops it.
  params.min_shared_free_ratio = 0;
  PairReport ungated;
  ASSERT_TRUE(
      RefineAndGate(side_a, {2, &a, &features_a_as_b}, params, touching, res, &times, &ungated)
          .ok());
  EXPECT_TRUE(ungated.accepted) << ungated.reason;

  // A map without free space has nothing to share.
  auto occupied_only = VoxelGrid::FromKeys(res, a.occupied_keys());
  ASSERT_TRUE(occupied_only.ok());
  EXPECT_FALSE(occupied_only->has_free_space());
  EXPECT_EQ(ComputeSharedFree(index, *occupied_only, right, 0).evaluated, 0u);
}

// A free leaf just below the root (a cube of 2^15 voxels a side, ~3.5e13
// voxels; hostile or not, a valid file) is sampled on a lattice of at most
// kMaxSharedFreePoints, not walked voxel by voxel, even when asked for all.
TEST(SharedFreeGateTest, AHugeFreeLeafIsSampledNotWalked) {
  auto tree = ReadOctree(testing::BtHeader("2", "0.1") + std::string("\x01\x00", 2));
  ASSERT_TRUE(tree.ok()) << tree.status().ToString();
  auto huge = VoxelGrid::FromOcTree(**tree);
  ASSERT_TRUE(huge.ok()) << huge.status().ToString();
  ASSERT_TRUE(huge->has_free_space());
  auto a = VoxelGrid::FromKeys(0.1, {VoxelKey(0, 0, 0)}, {VoxelKey(5, 5, 5)});
  ASSERT_TRUE(a.ok());
  const OverlapIndex index(*a);
  for (const std::size_t max_points : {std::size_t{0}, std::size_t{1000}}) {
    const SharedFree free =
        ComputeSharedFree(index, *huge, Eigen::Isometry3d::Identity(), max_points);
    EXPECT_GT(free.evaluated, 0u);
    EXPECT_LE(free.evaluated, max_points > 0 ? 2 * max_points : 2 * kMaxSharedFreePoints);
    EXPECT_GE(free.stride, 128);  // (2^45 / 2^24)^(1/3): 2^7
  }
}

// The wall of a round hall: the voxels whose centres lie within 0.55 voxel
// of a vertical cylinder of `radius_voxels` about `axis_voxels` (x, y), z in
// [0, height_voxels); no floor or ceiling, no free space. Turned about its
// axis it lies on itself: it fixes no yaw.
VoxelGrid RoundWall(const Eigen::Vector2d& axis_voxels, double radius_voxels, int height_voxels) {
  std::vector<VoxelKey> wall;
  const int reach = static_cast<int>(std::ceil(radius_voxels)) + 2;
  const int x0 = static_cast<int>(std::floor(axis_voxels.x()));
  const int y0 = static_cast<int>(std::floor(axis_voxels.y()));
  for (int x = x0 - reach; x <= x0 + reach; ++x) {
    for (int y = y0 - reach; y <= y0 + reach; ++y) {
      const double off_wall =
          (Eigen::Vector2d(x + 0.5, y + 0.5) - axis_voxels).norm() - radius_voxels;
      if (std::abs(off_wall) > 0.55) continue;
      for (int z = 0; z < height_voxels; ++z) wall.emplace_back(x, y, z);
    }
  }
  auto grid = VoxelGrid::FromKeys(kRoomResolutionM, wall);
  EXPECT_TRUE(grid.ok()) << grid.status().ToString();
  return grid.ok() ? std::move(grid).value() : VoxelGrid{};
}

// The restart-spread gate (MergeParams::max_restart_spread_voxels), the last
// of RefineAndGate's; MergeSubmaps cannot reach it here (a round wall has
// neither corners nor wall planes). B is a round hall's wall, 30 m across,
// on a lattice 0.3 / 0.6 voxel off A's and turned 30 deg (any yaw about the
// axis is as right as another). From the right answer ICP passes every other
// gate, but the restarts turned about the vertical stay turned, the wall
// lying on itself: at B's corners they end 2 sin(0.75 deg) x 212 voxels =
// 5.6 voxels from the answer, and the pair is refused. A room's walls fix
// the alignment: its restarts end together.
TEST(RestartSpreadGateTest, RefusesARoundHallWhoseWallFixesNoYaw) {
  constexpr double kRadius = 150.0;  // voxels
  const VoxelGrid a = RoundWall({0.0, 0.0}, kRadius, 20);
  const Eigen::Vector3d b_axis(40.3, -20.6, 0.0);  // voxels, in B's frame
  const VoxelGrid b = RoundWall(b_axis.head<2>(), kRadius, 20);
  // B's axis onto A's, turned 30 deg about it.
  const Eigen::Isometry3d right =
      Pose(30, 0, 0, Eigen::Vector3d::Zero()) * Eigen::Translation3d(-kRoomResolutionM * b_axis);
  // Where a restart turned by restart_turn_deg about the axis ends (ICP
  // cannot turn it back): B's farthest corner from the axis moves by this.
  MergeParams params;
  double corner_from_axis_m = 0;
  for (const double x : {b.min_corner().x(), b.max_corner().x()}) {
    for (const double y : {b.min_corner().y(), b.max_corner().y()}) {
      corner_from_axis_m = std::max(
          corner_from_axis_m, (Eigen::Vector2d(x, y) - kRoomResolutionM * b_axis.head<2>()).norm());
    }
  }
  const double turned_voxels = 2 * std::sin(0.5 * params.restart_turn_deg * M_PI / 180.0) *
                               corner_from_axis_m / kRoomResolutionM;
  ASSERT_GT(turned_voxels, params.max_restart_spread_voxels + 1);

  SubmapFeatures features_a(1, &a, &params), features_b(2, &b, &params);
  const PairSide side_a{1, &a, &features_a}, side_b{2, &b, &features_b};
  StageTimes times;
  PairReport refused;
  ASSERT_TRUE(
      RefineAndGate(side_a, side_b, params, right, kRoomResolutionM, &times, &refused).ok());
  EXPECT_FALSE(refused.accepted);
  EXPECT_NE(refused.reason.find("ICP restarts turned by 1.5 deg end up to "), std::string::npos)
      << refused.reason;
  EXPECT_NE(refused.reason.find(" voxels apart at B's corners, above 4.00"), std::string::npos)
      << refused.reason;
  EXPECT_NEAR(refused.restart_spread_voxels, turned_voxels, 0.3);
  // Every gate before it passed.
  EXPECT_LE(refused.residual_m / kRoomResolutionM, params.max_residual_voxels);
  EXPECT_GE(refused.overlap_score, params.min_overlap_score);
  EXPECT_GE(refused.support_fraction, params.min_support_fraction);
  EXPECT_LT(testing::RotationErrorDeg(refused.T_a_b, right), 0.1);

  // Above the spread, the gate lets it through, with the figure recorded.
  params.max_restart_spread_voxels = 2 * turned_voxels;
  PairReport raised;
  ASSERT_TRUE(RefineAndGate(side_a, side_b, params, right, kRoomResolutionM, &times, &raised).ok());
  EXPECT_TRUE(raised.accepted) << raised.reason;
  EXPECT_NEAR(raised.restart_spread_voxels, turned_voxels, 0.3);

  // Overlapping crops of the furnished room, placed right: the restarts end
  // within a voxel of the answer under the default gate.
  VoxelGrid room_a, room_b;
  ASSERT_NO_FATAL_FAILURE(OverlappingRoomGrids(&room_a, &room_b));
  const MergeParams defaults;
  SubmapFeatures features_room_a(1, &room_a, &defaults), features_room_b(2, &room_b, &defaults);
  PairReport room;
  ASSERT_TRUE(RefineAndGate({1, &room_a, &features_room_a}, {2, &room_b, &features_room_b},
                            defaults, Eigen::Isometry3d::Identity(), kRoomResolutionM, &times,
                            &room)
                  .ok());
  EXPECT_TRUE(room.accepted) << room.reason;
  EXPECT_GE(room.restart_spread_voxels, 0.0);
  EXPECT_LT(room.restart_spread_voxels, 1.0);
}

TEST(InspectSubmapTest, SummarisesAValidMap) {
  const std::string a = RasteriseSubmap(FurnishedRoom(), RoomCropX(-0.5, 5.6),
                                        Eigen::Isometry3d::Identity(), kRoomResolutionM);
  auto summary = InspectSubmap(a);
  ASSERT_TRUE(summary.ok()) << summary.status().ToString();
  EXPECT_EQ(summary->resolution, kRoomResolutionM);
  EXPECT_GT(summary->occupied_voxels, 10000u);
  EXPECT_GT(summary->free_voxels, 40000u);
  // The wall x = 0.05 m is the voxel [0, 0.1), the ceiling z = 2.55 m [2.5, 2.6).
  EXPECT_NEAR(summary->bounds_min.x(), 0.0, 1e-9);
  EXPECT_NEAR(summary->bounds_max.z(), 2.6, 1e-9);
  auto bad = InspectSubmap("not an octree");
  ASSERT_FALSE(bad.ok());
  EXPECT_EQ(bad.status().code(), StatusCode::kInvalidArgument);
}

}  // namespace
}  // namespace mapd::voxel
