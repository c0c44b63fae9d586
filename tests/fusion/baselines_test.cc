// The Fuser interface, the two competing methods (hand-checked cases), and the
// scenario generator (determinism, extraction near the true walls, metrics).
#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include "eval/baselines/density_fuser.h"
#include "eval/baselines/mean_shift.h"
#include "eval/fuser_registry.h"
#include "eval/metrics.h"
#include "sim/city_scenario.h"

namespace mapd::fusion {
namespace {

using geometry::Segment2;
using geometry::Vec2;

GroundFeature Wall(FeatureId id, Vec2 a, Vec2 b) {
  GroundFeature f;
  f.id = id;
  f.segment = {a, b};
  return f;
}

std::unique_ptr<Fuser> Make(const std::string& name) {
  FuserOptions options;
  options.three_criteria.min_support = 1;
  auto fuser = MakeFuser(name, options);
  EXPECT_TRUE(fuser.ok()) << fuser.status().ToString();
  return std::move(fuser.value());
}

// Three noisy views of the wall y = 0, x in [0, 10], one per observation.
void AddThreeViewsOfOneWall(Fuser* fuser, double y_offset_m, FeatureId first_id) {
  const double dy[3] = {0.02, -0.01, 0.0};
  for (int k = 0; k < 3; ++k) {
    ASSERT_TRUE(fuser
                    ->Add(first_id + k, 0,
                          {Wall(first_id + k, {0.5 * k, y_offset_m + dy[k]},
                                {8.0 + k, y_offset_m - dy[k]})},
                          nullptr)
                    .ok());
  }
}

class EveryFuserTest : public ::testing::TestWithParam<std::string> {};

TEST_P(EveryFuserTest, MergesThreeViewsOfOneWall) {
  std::unique_ptr<Fuser> fuser = Make(GetParam());
  EXPECT_EQ(fuser->name(), GetParam());
  AddThreeViewsOfOneWall(fuser.get(), 0.0, 1);
  const std::vector<FusedFeature> map = fuser->Published();
  ASSERT_EQ(map.size(), 1u);
  EXPECT_EQ(map[0].id, 1u);
  EXPECT_EQ(map[0].member_count, 3u);
  // The extent of all views: x from 0 to 10, on y ~ 0.
  const double x_lo = std::min(map[0].segment.a.x(), map[0].segment.b.x());
  const double x_hi = std::max(map[0].segment.a.x(), map[0].segment.b.x());
  EXPECT_NEAR(x_lo, 0.0, 0.01);
  EXPECT_NEAR(x_hi, 10.0, 0.01);
  EXPECT_NEAR(map[0].segment.a.y(), 0.0, 0.02);
  EXPECT_NEAR(map[0].segment.b.y(), 0.0, 0.02);
}

TEST_P(EveryFuserTest, SeparatesParallelWallsTwoMetresApart) {
  std::unique_ptr<Fuser> fuser = Make(GetParam());
  AddThreeViewsOfOneWall(fuser.get(), 0.0, 1);
  AddThreeViewsOfOneWall(fuser.get(), 2.0, 11);
  const std::vector<FusedFeature> map = fuser->Published();
  ASSERT_EQ(map.size(), 2u);
  // Each wall is its own three views, named by its first feature.
  EXPECT_EQ(map[0].id, 1u);
  EXPECT_EQ(map[0].member_count, 3u);
  EXPECT_EQ(map[1].id, 11u);
  EXPECT_EQ(map[1].member_count, 3u);
  EXPECT_NEAR(map[0].segment.midpoint().y(), 0.0, 0.02);
  EXPECT_NEAR(map[1].segment.midpoint().y(), 2.0, 0.02);
}

TEST_P(EveryFuserTest, SeparatesPerpendicularWallsAndJoinsTheirCorner) {
  std::unique_ptr<Fuser> fuser = Make(GetParam());
  // An L: y = 0 for x in [0, 10] and x = 10 for y in [0, 6], three views each,
  // every view stopping 0.2 m short of the corner (10, 0).
  for (int k = 0; k < 3; ++k) {
    const double e = 0.01 * k;
    ASSERT_TRUE(fuser
                    ->Add(k + 1, 0,
                          {Wall(10 * k + 1, {0, e}, {9.8, e}),
                           Wall(10 * k + 2, {10 - e, 0.2}, {10 - e, 6})},
                          nullptr)
                    .ok());
  }
  const std::vector<FusedFeature> map = fuser->Published();
  ASSERT_EQ(map.size(), 2u);
  EXPECT_EQ(map[0].id, 1u);  // the horizontal views
  EXPECT_EQ(map[0].member_count, 3u);
  EXPECT_EQ(map[1].id, 2u);  // the vertical ones
  EXPECT_EQ(map[1].member_count, 3u);
  // Both fused walls end at the corner optimisation's joint point, near (10, 0).
  int at_corner = 0;
  for (const FusedFeature& f : map) {
    for (const Vec2& p : {f.segment.a, f.segment.b}) at_corner += (p - Vec2(10, 0)).norm() < 0.05;
  }
  EXPECT_EQ(at_corner, 2);
}

// Refused with InvalidArgument and a message that names the fault.
void ExpectRefused(const Status& status, const std::string& what) {
  EXPECT_EQ(status.code(), StatusCode::kInvalidArgument) << status.ToString();
  EXPECT_NE(status.message().find(what), std::string::npos) << status.ToString();
}

TEST_P(EveryFuserTest, RefusesBadInputUnchanged) {
  std::unique_ptr<Fuser> fuser = Make(GetParam());
  ASSERT_TRUE(fuser->Add(1, 0, {Wall(1, {0, 0}, {5, 0})}, nullptr).ok());
  ExpectRefused(fuser->Add(1, 0, {Wall(2, {0, 0}, {5, 0})}, nullptr), "observation 1 was added");
  ExpectRefused(fuser->Add(2, 0, {Wall(1, {0, 0}, {5, 0})}, nullptr),
                "features[0]: feature id 1 is not unique");
  ExpectRefused(fuser->Add(3, 0, {Wall(3, {0, 0}, {0, 0})}, nullptr),
                "features[0] has zero length");
  ExpectRefused(fuser->Add(4, 0, {Wall(4, {0, 0}, {NAN, 0})}, nullptr), "not finite");
  // A batch with one bad feature is refused whole: its good feature is not kept.
  ExpectRefused(fuser->Add(5, 0, {Wall(5, {0, 1}, {5, 1}), Wall(6, {0, 0}, {0, 0})}, nullptr),
                "features[1] has zero length");
  // Unchanged: the one wall of the first batch, as it was.
  const std::vector<FusedFeature> map = fuser->Published();
  ASSERT_EQ(map.size(), 1u);
  EXPECT_EQ(map[0].id, 1u);
  EXPECT_EQ(map[0].member_count, 1u);
  EXPECT_EQ(map[0].support, 1u);
  EXPECT_NEAR(std::min(map[0].segment.a.x(), map[0].segment.b.x()), 0.0, 1e-9);
  EXPECT_NEAR(std::max(map[0].segment.a.x(), map[0].segment.b.x()), 5.0, 1e-9);
  // The refused ids are still free.
  EXPECT_TRUE(fuser->Add(5, 0, {Wall(5, {20, 20}, {25, 20})}, nullptr).ok());
  EXPECT_EQ(fuser->Published().size(), 2u);
}

TEST_P(EveryFuserTest, ReportsChanges) {
  std::unique_ptr<Fuser> fuser = Make(GetParam());
  ChangeFeed feed;
  ASSERT_TRUE(fuser->Add(1, 0, {Wall(5, {0, 0}, {10, 0})}, &feed).ok());
  EXPECT_EQ(feed.added, std::vector<ClusterId>{5});
  EXPECT_TRUE(feed.updated.empty());
  EXPECT_TRUE(feed.removed.empty());
  ASSERT_TRUE(fuser->Add(2, 0, {Wall(3, {0, 0.01}, {10, 0.01})}, &feed).ok());
  // The cluster is now named by its smallest member: 5 is gone, 3 is new.
  EXPECT_EQ(feed.added, std::vector<ClusterId>{3});
  EXPECT_TRUE(feed.updated.empty());
  EXPECT_EQ(feed.removed, std::vector<ClusterId>{5});
  // A third view 3 cm off moves the wall (and is close enough to be no second
  // wall for the chain guard): an update of 3.
  ASSERT_TRUE(fuser->Add(3, 0, {Wall(7, {0, 0.03}, {10, 0.03})}, &feed).ok());
  EXPECT_TRUE(feed.added.empty());
  EXPECT_EQ(feed.updated, std::vector<ClusterId>{3});
  EXPECT_TRUE(feed.removed.empty());
  // A failed Add reports nothing.
  EXPECT_FALSE(fuser->Add(3, 0, {Wall(8, {0, 0}, {10, 0})}, &feed).ok());
  EXPECT_TRUE(feed.empty());
}

INSTANTIATE_TEST_SUITE_P(AllStrategies, EveryFuserTest,
                         ::testing::Values("three_criteria", "mean_shift", "density"));

TEST(FuserRegistryTest, UnknownNameIsRefusedWithTheKnownOnes) {
  auto fuser = MakeFuser("hough", FuserOptions());
  ASSERT_FALSE(fuser.ok());
  EXPECT_EQ(fuser.status().code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(fuser.status().message(),
            "unknown fusion strategy \"hough\" (known: three_criteria, mean_shift, density)");
}

TEST(FuserRegistryTest, InvalidBaselineParametersAreRefused) {
  // Each refusal names the parameter at fault.
  FuserOptions options;
  options.mean_shift.centre.bandwidth_m = 0.0;
  ExpectRefused(MakeFuser("mean_shift", options).status(), "mean_shift.centre.bandwidth_m");
  options = FuserOptions();
  options.mean_shift.post.snap_m = -1.0;
  ExpectRefused(MakeFuser("mean_shift", options).status(), "mean_shift.post.snap_m");
  options = FuserOptions();
  options.density.orientation.bandwidth_rad = -1.0;
  ExpectRefused(MakeFuser("density", options).status(), "density.orientation.bandwidth_rad");
  options = FuserOptions();
  options.density.orientation.bin_rad = 2.0 * options.density.orientation.bandwidth_rad;
  ExpectRefused(MakeFuser("density", options).status(), "density.orientation.bin_rad");
  options = FuserOptions();
  options.density.min_pts = 0;
  ExpectRefused(MakeFuser("density", options).status(), "density.min_pts");
  options = FuserOptions();
  options.three_criteria.gamma = 2.0;
  ExpectRefused(MakeFuser("three_criteria", options).status(), "gamma");
  // The defaults are valid.
  for (const std::string& name : FuserNames()) {
    EXPECT_TRUE(MakeFuser(name, FuserOptions()).ok()) << name;
  }
}

TEST(MeanShiftTest, OrientationModesWrapAroundPi) {
  // 1 deg and 179 deg are 2 deg apart on the axial circle; 90 deg is its own mode.
  const double deg = M_PI / 180.0;
  const std::vector<double> theta = {1 * deg, 179 * deg, 0.5 * deg, 90 * deg, 91 * deg};
  const baselines::Modes modes =
      baselines::OrientationModes(theta, std::vector<double>(theta.size(), 1.0), {});
  ASSERT_EQ(modes.mode.size(), 2u);
  ASSERT_EQ(modes.label.size(), theta.size());
  EXPECT_EQ(modes.label[0], modes.label[1]);
  EXPECT_EQ(modes.label[0], modes.label[2]);
  EXPECT_EQ(modes.label[3], modes.label[4]);
  EXPECT_NE(modes.label[0], modes.label[3]);
  // Where the modes are: in [0, pi); the wrapped mean of 1, -1 and 0.5 deg,
  // near 0 (or pi), and between 90 and 91 deg.
  for (double mode : modes.mode) {
    EXPECT_GE(mode, 0.0);
    EXPECT_LT(mode, M_PI);
  }
  const double near_zero = modes.mode[modes.label[0]];
  EXPECT_LT(std::min(near_zero, M_PI - near_zero), 1.0 * deg) << near_zero / deg;
  EXPECT_GT(modes.mode[modes.label[3]], 90 * deg - 1e-9);
  EXPECT_LT(modes.mode[modes.label[3]], 91 * deg + 1e-9);
}

TEST(MeanShiftTest, CentreModesFindTwoBlobs) {
  std::vector<Vec2> points;
  for (int k = 0; k < 10; ++k) points.push_back(Vec2(0.1 * k, 0.0));
  for (int k = 0; k < 10; ++k) points.push_back(Vec2(10.0 + 0.1 * k, 0.0));
  std::vector<Vec2> modes;
  const std::vector<uint32_t> label = baselines::CentreModes(points, {}, &modes);
  ASSERT_EQ(modes.size(), 2u);
  ASSERT_EQ(label.size(), points.size());
  for (int k = 1; k < 10; ++k) EXPECT_EQ(label[static_cast<size_t>(k)], label[0]);
  for (int k = 11; k < 20; ++k) EXPECT_EQ(label[static_cast<size_t>(k)], label[10]);
  EXPECT_NE(label[0], label[10]);
  // The modes are the blobs' centres (flat kernel: each blob's mean).
  EXPECT_LT((modes[label[0]] - Vec2(0.45, 0.0)).norm(), 1e-9);
  EXPECT_LT((modes[label[10]] - Vec2(10.45, 0.0)).norm(), 1e-9);
}

TEST(DensityTest, NeighbourTestIsLateralAndLongitudinal) {
  const Segment2 f{{0, 0}, {10, 0}};
  EXPECT_TRUE(baselines::DensityNeighbours(f, {{9, 0.1}, {15, 0.1}}, 0.3, 0.0));   // overlap 1 m
  EXPECT_FALSE(baselines::DensityNeighbours(f, {{11, 0}, {15, 0}}, 0.3, 0.0));     // gap 1 m
  EXPECT_TRUE(baselines::DensityNeighbours(f, {{11, 0}, {15, 0}}, 0.3, -1.5));     // gap allowed
  EXPECT_FALSE(baselines::DensityNeighbours(f, {{0, 0.5}, {10, 0.5}}, 0.3, 0.0));  // 0.5 m apart
}

// ---- The scenario generator ------------------------------------------------

scenario::ScenarioParams SmallWorld(uint64_t seed) {
  scenario::ScenarioParams p;
  p.seed = seed;
  p.blocks_x = 3;
  p.blocks_y = 2;
  return p;
}

TEST(ScenarioTest, SameSeedSameScene) {
  const scenario::World w1 = scenario::GenerateWorld(SmallWorld(7));
  const scenario::World w2 = scenario::GenerateWorld(SmallWorld(7));
  ASSERT_EQ(w1.structures.size(), w2.structures.size());
  for (size_t k = 0; k < w1.structures.size(); ++k) {
    EXPECT_EQ(w1.structures[k].segment.a, w2.structures[k].segment.a);
    EXPECT_EQ(w1.structures[k].segment.b, w2.structures[k].segment.b);
  }
  const scenario::ScanSimulator s1(SmallWorld(7), w1), s2(SmallWorld(7), w2);
  ASSERT_EQ(s1.size(), s2.size());
  for (size_t k = 0; k < s1.size(); k += 37) {
    const scenario::Scan a = s1.Simulate(k), b = s2.Simulate(k);
    ASSERT_EQ(a.features.size(), b.features.size());
    for (size_t i = 0; i < a.features.size(); ++i) {
      EXPECT_EQ(a.features[i].id, b.features[i].id);
      EXPECT_EQ(a.features[i].segment.a, b.features[i].segment.a);
      EXPECT_EQ(a.features[i].segment.b, b.features[i].segment.b);
    }
  }
}

TEST(ScenarioTest, OtherSeedOtherScene) {
  const scenario::World w1 = scenario::GenerateWorld(SmallWorld(7));
  const scenario::World w2 = scenario::GenerateWorld(SmallWorld(8));
  EXPECT_NE(w1.structures[0].segment.a, w2.structures[0].segment.a);
}

TEST(ScenarioTest, WorldHasWallsCornersClosePairsAndTrivialStructures) {
  scenario::ScenarioParams p = SmallWorld(3);
  p.close_pair_prob = 1.0;  // every block a pair
  const scenario::World w = scenario::GenerateWorld(p);
  EXPECT_EQ(w.buildings.size(), 12u);
  EXPECT_EQ(w.wall_count, 4 * w.buildings.size());
  EXPECT_EQ(w.corners.size(), 4 * w.buildings.size());
  ASSERT_EQ(w.close_pairs.size(), 6u);
  for (const auto& [b1, b2] : w.close_pairs) {
    // The gap: from the line of b1's east wall (corners 1-2) to b2's west wall (corner 0).
    const Vec2 p1 = w.buildings[static_cast<size_t>(b1)][1];
    const Vec2 u = (w.buildings[static_cast<size_t>(b1)][2] - p1).normalized();
    const Vec2 d = w.buildings[static_cast<size_t>(b2)][0] - p1;
    const double gap = std::abs(u.x() * d.y() - u.y() * d.x());
    EXPECT_GE(gap, 1.0 - 1e-9);
    EXPECT_LE(gap, 2.0 + 1e-9);
  }
  for (const scenario::Corner& c : w.corners) {
    EXPECT_LT((w.structures[static_cast<size_t>(c.in)].segment.b - c.point).norm(), 1e-12);
    EXPECT_LT((w.structures[static_cast<size_t>(c.out)].segment.a - c.point).norm(), 1e-12);
  }
  EXPECT_GT(w.structures.size(), w.wall_count);  // fences and poles
  EXPECT_FALSE(w.route.empty());
}

TEST(ScenarioTest, ExtractedSegmentsLieNearTheirTrueWalls) {
  // No pose noise: an extracted segment is a TLS fit to >= 8 returns with 2 cm
  // noise, so its endpoints lie within a few cm of the wall it came from.
  const scenario::ScenarioParams p = SmallWorld(5);
  const scenario::World w = scenario::GenerateWorld(p);
  const scenario::ScanSimulator sim(p, w);
  size_t on_walls = 0, total = 0;
  for (size_t k = 0; k < sim.size(); k += 5) {
    const scenario::Scan scan = sim.Simulate(k);
    for (size_t i = 0; i < scan.features.size(); ++i) {
      ++total;
      const int t = scan.truth[i];
      ASSERT_GE(t, 0);
      if (static_cast<size_t>(t) >= w.wall_count) continue;
      ++on_walls;
      const Segment2& wall = w.structures[static_cast<size_t>(t)].segment;
      EXPECT_LT(geometry::PointSegmentDistance(scan.features[i].segment.a, wall), 0.15);
      EXPECT_LT(geometry::PointSegmentDistance(scan.features[i].segment.b, wall), 0.15);
    }
  }
  EXPECT_GT(total, 200u);
  EXPECT_GT(on_walls, total / 2);
}

TEST(MetricsTest, VertexErrorIsTheSumOfEndpointDistancesAtACorner) {
  // One 10 x 6 building; the "map" has its four walls, two ends moved.
  scenario::World w;
  w.buildings.push_back({{0, 0}, {10, 0}, {10, 6}, {0, 6}});
  for (int k = 0; k < 4; ++k) {
    w.structures.push_back(
        {{w.buildings[0][static_cast<size_t>(k)], w.buildings[0][static_cast<size_t>((k + 1) % 4)]},
         scenario::StructureKind::kWall,
         0});
    w.corners.push_back({w.buildings[0][static_cast<size_t>(k)], (k + 3) % 4, k});
  }
  w.wall_count = 4;
  // Raw: three scans see all walls fully.
  std::vector<scenario::Scan> raw(3);
  for (size_t s = 0; s < 3; ++s) {
    raw[s].observation = s + 1;
    for (int k = 0; k < 4; ++k) {
      raw[s].features.push_back(Wall(s * 4 + k, w.structures[static_cast<size_t>(k)].segment.a,
                                     w.structures[static_cast<size_t>(k)].segment.b));
      raw[s].truth.push_back(k);
    }
  }
  std::vector<FusedFeature> map(4);
  for (int k = 0; k < 4; ++k) {
    map[static_cast<size_t>(k)].id = static_cast<ClusterId>(k);
    map[static_cast<size_t>(k)].segment = w.structures[static_cast<size_t>(k)].segment;
  }
  map[0].segment.b = {10.03, 0.0};  // wall 0 overshoots corner (10, 0) by 3 cm
  map[1].segment.a = {10.0, 0.04};  // wall 1 stops 4 cm short of it
  map.push_back(FusedFeature());    // and one spurious feature
  map.back().id = 9;
  map.back().segment = {{3, 3}, {4, 3}};
  const scenario::MapMetrics m = scenario::Evaluate(w, raw, map, scenario::MetricsParams());
  EXPECT_EQ(m.fused, 5u);
  EXPECT_EQ(m.spurious, 1u);
  EXPECT_EQ(m.walls_seen, 4u);
  EXPECT_EQ(m.walls_matched, 4u);
  ASSERT_EQ(m.corners_met, 4u);
  EXPECT_NEAR(m.vertex_errors_m[1], 0.07, 1e-12);  // corner 1 = (10, 0)
  EXPECT_NEAR(m.vertex_errors_m[0], 0.0, 1e-12);
  // Wall 1 is covered from 4 cm on: (32 - 0.04) / 32 of the perimeter.
  EXPECT_NEAR(m.completeness, (32.0 - 0.04) / 32.0, 1e-9);
}

}  // namespace
}  // namespace mapd::fusion
