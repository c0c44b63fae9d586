// PlaneFusionEngine: the three criteria, publication, order independence on a
// small set, bad input, folding on a revisited floor, snapshots.
#include "fusion/plane_engine.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <random>
#include <string>
#include <vector>

#include "fusion/plane_geometry.h"

namespace mapd::fusion {
namespace {

using Eigen::Vector3d;

constexpr double kDeg = 3.14159265358979323846 / 180.0;

// A rectangle [x0, x1] x [y0, y1] at height z, optionally tilted about the
// x axis by `tilt_rad` around its centre.
MapPlane Rect(FeatureId id, double x0, double y0, double x1, double y1, double z,
              double tilt_rad = 0.0) {
  MapPlane p;
  p.id = id;
  const double cy = 0.5 * (y0 + y1);
  const auto at = [&](double x, double y) {
    return Vector3d(x, cy + (y - cy) * std::cos(tilt_rad), z + (y - cy) * std::sin(tilt_rad));
  };
  p.boundary = {at(x0, y0), at(x1, y0), at(x1, y1), at(x0, y1)};
  p.normal = Vector3d(0, -std::sin(tilt_rad), std::cos(tilt_rad));
  p.offset_m = -p.normal.dot(p.boundary[0]);
  return p;
}

// Fuses observation by observation (one plane each) and reports whether a and b ended in one
// cluster.
bool Linked(const PlaneFusionParams& params, const MapPlane& a, const MapPlane& b) {
  PlaneFusionEngine engine(params);
  EXPECT_TRUE(engine.Add(1, 1, {a}).ok());
  EXPECT_TRUE(engine.Add(2, 1, {b}).ok());
  return engine.cluster_count() == 1;
}

TEST(PlaneFusionParamsTest, DefaultsAreValidAndBadValuesAreNamed) {
  EXPECT_TRUE(PlaneFusionParams{}.Validate().ok());
  PlaneFusionParams p;
  p.max_normal_angle_rad = -1;
  EXPECT_NE(p.Validate().message().find("max_normal_angle_rad"), std::string::npos);
  p = {};
  p.min_overlap = 1.5;
  EXPECT_NE(p.Validate().message().find("min_overlap"), std::string::npos);
  p = {};
  p.max_gap_m = NAN;
  EXPECT_NE(p.Validate().message().find("max_gap_m"), std::string::npos);
  p = {};
  p.min_support = 0;
  EXPECT_FALSE(PlaneFusionEngine::Create(p).ok());
}

TEST(PlaneCriteriaTest, OverlappingFloorPatchesLink) {
  EXPECT_TRUE(Linked({}, Rect(1, 0, 0, 4, 4, 0.0), Rect(2, 2, 2, 6, 6, 0.02)));
}

TEST(PlaneCriteriaTest, NormalAngleBeyondTheLimitDoesNotLink) {
  PlaneFusionParams p;
  p.max_offset_m = 1.0;  // isolate criterion 1
  EXPECT_TRUE(Linked(p, Rect(1, 0, 0, 2, 2, 0.0), Rect(2, 0, 0, 2, 2, 0.0, 4 * kDeg)));
  EXPECT_FALSE(Linked(p, Rect(1, 0, 0, 2, 2, 0.0), Rect(2, 0, 0, 2, 2, 0.0, 6 * kDeg)));
}

TEST(PlaneCriteriaTest, OffsetBeyondTheLimitDoesNotLink) {
  EXPECT_TRUE(Linked({}, Rect(1, 0, 0, 4, 4, 0.0), Rect(2, 0, 0, 4, 4, 0.09)));
  EXPECT_FALSE(Linked({}, Rect(1, 0, 0, 4, 4, 0.0), Rect(2, 0, 0, 4, 4, 0.11)));
  // A floor and the ceiling above it never link.
  EXPECT_FALSE(Linked({}, Rect(1, 0, 0, 4, 4, 0.0), Rect(2, 0, 0, 4, 4, 2.5)));
}

TEST(PlaneCriteriaTest, GapAndOverlap) {
  EXPECT_TRUE(Linked({}, Rect(1, 0, 0, 4, 4, 0.0), Rect(2, 4.25, 0, 8, 4, 0.0)));   // 0.25 m gap
  EXPECT_FALSE(Linked({}, Rect(1, 0, 0, 4, 4, 0.0), Rect(2, 4.35, 0, 8, 4, 0.0)));  // 0.35 m gap
  PlaneFusionParams p;
  p.min_overlap = 0.5;  // of the smaller patch
  EXPECT_TRUE(Linked(p, Rect(1, 0, 0, 4, 4, 0.0), Rect(2, 1, 1, 3, 3, 0.0)));     // contained
  EXPECT_TRUE(Linked(p, Rect(1, 0, 0, 4, 4, 0.0), Rect(2, 2, 0, 6, 4, 0.0)));     // half
  EXPECT_FALSE(Linked(p, Rect(1, 0, 0, 4, 4, 0.0), Rect(2, 3, 0, 7, 4, 0.0)));    // a quarter
  EXPECT_FALSE(Linked(p, Rect(1, 0, 0, 4, 4, 0.0), Rect(2, 4.1, 0, 8, 4, 0.0)));  // gap, no overlap
}

TEST(PlaneCriteriaTest, PlanesOfOneObservationAreNotLinked) {
  PlaneFusionEngine engine({});
  ASSERT_TRUE(engine.Add(1, 1, {Rect(1, 0, 0, 4, 4, 0), Rect(2, 1, 1, 5, 5, 0)}).ok());
  EXPECT_EQ(engine.cluster_count(), 2u);
}

TEST(PlaneFusionEngineTest, PublishesAtMinSupportWithFittedPlaneAndHull) {
  PlaneFusionEngine engine({});
  PlaneChangeFeed feed;
  ASSERT_TRUE(engine.Add(10, 1, {Rect(100, 0, 0, 4, 4, 0.01)}, &feed).ok());
  ASSERT_TRUE(engine.Add(11, 2, {Rect(110, 2, 0, 6, 4, 0.01)}, &feed).ok());
  EXPECT_TRUE(engine.Published().empty());
  EXPECT_TRUE(feed.empty());
  MapPlane flipped = Rect(120, 1, -1, 5, 3, 0.01);
  flipped.normal = -flipped.normal;  // a normal's sign does not matter
  flipped.offset_m = -flipped.offset_m;
  ASSERT_TRUE(engine.Add(12, 1, {flipped}, &feed).ok());
  ASSERT_EQ(feed.added, std::vector<ClusterId>{100});
  const std::vector<FusedPlane> published = engine.Published();
  ASSERT_EQ(published.size(), 1u);
  const FusedPlane& f = published[0];
  EXPECT_EQ(f.id, 100u);
  EXPECT_EQ(f.support, 3u);
  EXPECT_EQ(f.member_count, 3u);
  EXPECT_EQ(f.robots, (std::vector<RobotId>{1, 2}));
  EXPECT_NEAR(f.normal.z(), 1.0, 1e-9);
  EXPECT_NEAR(-f.offset_m, 0.01, 1e-9);  // the mean height of the boundary points
  EXPECT_NEAR(f.area_m2, 6.0 * 5.0 - 2 * 0.5 * 1 * 1, 1e-6);  // hull of the three rectangles
  ASSERT_GE(f.boundary.size(), 4u);
  for (const Vector3d& p : f.boundary) EXPECT_NEAR(f.normal.dot(p) + f.offset_m, 0.0, 1e-9);
  // Counter-clockwise about the normal.
  double turn = 0;
  for (size_t i = 0; i < f.boundary.size(); ++i) {
    const Vector3d& a = f.boundary[i];
    const Vector3d& b = f.boundary[(i + 1) % f.boundary.size()];
    turn += f.normal.dot(a.cross(b));
  }
  EXPECT_GT(turn, 0);
  EXPECT_NEAR(f.z_min_m, 0.01, 1e-9);
  ASSERT_TRUE(engine.Get(100).has_value());
  EXPECT_FALSE(engine.Get(110).has_value());
}

TEST(PlaneFusionEngineTest, MergingClustersRemovesThePublishedLarger) {
  PlaneFusionParams p;
  p.min_support = 1;
  PlaneFusionEngine engine(p);
  PlaneChangeFeed feed;
  ASSERT_TRUE(engine.Add(1, 1, {Rect(10, 0, 0, 2, 2, 0)}).ok());
  ASSERT_TRUE(engine.Add(2, 1, {Rect(20, 5, 0, 7, 2, 0)}).ok());
  ASSERT_EQ(engine.published_count(), 2u);
  ASSERT_TRUE(engine.Add(3, 1, {Rect(30, 1, 0, 6, 2, 0)}, &feed).ok());  // bridges both
  EXPECT_EQ(feed.updated, std::vector<ClusterId>{10});
  EXPECT_EQ(feed.removed, std::vector<ClusterId>{20});
  EXPECT_EQ(engine.published_count(), 1u);
}

// Two floor levels, a ramp between them and a ceiling, seen by four robots.
std::vector<std::vector<MapPlane>> SmallSite() {
  std::vector<std::vector<MapPlane>> obs;
  for (FeatureId o = 1; o <= 6; ++o) {
    const double d = 0.05 * static_cast<double>(o % 3);
    const double h = 0.01 * static_cast<double>(o % 2);
    const FeatureId base = o << 8;
    obs.push_back({Rect(base + 1, d, d, 5 + d, 4, h), Rect(base + 2, 8 + d, 0, 12, 4 - d, 1.0 + h),
                   Rect(base + 3, 5.2, 0.5 + d, 7.8, 3.5, 0.5 + h, 8 * kDeg),
                   Rect(base + 4, 0, 0, 5 - d, 4, 2.6 - h)});
  }
  return obs;
}

TEST(PlaneFusionEngineTest, ResultDoesNotDependOnObservationOrder) {
  const auto obs = SmallSite();
  std::vector<size_t> order(obs.size());
  for (size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::vector<FusedPlane> reference;
  std::mt19937 rng(7);
  for (int trial = 0; trial < 8; ++trial) {
    PlaneFusionEngine engine({});
    for (size_t i : order) ASSERT_TRUE(engine.Add(i + 1, i % 4, obs[i]).ok());
    std::vector<FusedPlane> published = engine.Published();
    if (trial == 0) {
      reference = published;
      ASSERT_EQ(reference.size(), 4u);
    } else {
      ASSERT_EQ(published.size(), reference.size());
      for (size_t k = 0; k < published.size(); ++k) {
        const FusedPlane &a = published[k], &b = reference[k];
        EXPECT_EQ(a.id, b.id);
        EXPECT_EQ(a.support, b.support);
        EXPECT_EQ(a.member_count, b.member_count);
        EXPECT_EQ(a.robots, b.robots);
        EXPECT_NEAR((a.normal - b.normal).norm(), 0.0, 1e-9);
        EXPECT_NEAR(a.offset_m, b.offset_m, 1e-9);
        EXPECT_NEAR(a.area_m2, b.area_m2, 1e-6);
      }
    }
    std::shuffle(order.begin(), order.end(), rng);
  }
}

TEST(PlaneFusionEngineTest, BadInputIsRefusedAndChangesNothing) {
  PlaneFusionEngine engine({});
  ASSERT_TRUE(engine.Add(1, 1, {Rect(1, 0, 0, 4, 4, 0)}).ok());
  std::vector<MapPlane> bad = {Rect(10, 0, 0, 4, 4, 0), Rect(11, 0, 0, 4, 4, 0)};
  bad[1].boundary[2].x() = NAN;
  Status s = engine.Add(2, 1, bad);
  EXPECT_EQ(s.code(), StatusCode::kInvalidArgument);
  EXPECT_NE(s.message().find("planes[1].boundary[2]"), std::string::npos) << s.message();
  bad[1] = Rect(11, 0, 0, 4, 4, 0);
  bad[1].normal *= 2;
  EXPECT_NE(engine.Add(2, 1, bad).message().find("planes[1]: normal is not unit"),
            std::string::npos);
  bad[1] = Rect(11, 0, 0, 4, 4, 0);
  bad[1].boundary.resize(2);
  EXPECT_NE(engine.Add(2, 1, bad).message().find("planes[1]: boundary has 2 points"),
            std::string::npos);
  bad[1] = Rect(10, 0, 0, 4, 4, 0);
  EXPECT_NE(engine.Add(2, 1, bad).message().find("used twice"), std::string::npos);
  bad[1] = Rect(11, 0, 0, 4, 4, 0);
  bad[1].offset_m = INFINITY;
  EXPECT_NE(engine.Add(2, 1, bad).message().find("planes[1]"), std::string::npos);
  EXPECT_EQ(engine.plane_count(), 1u);
  EXPECT_EQ(engine.cluster_count(), 1u);
}

// A floor seen again and again with a little noise.
MapPlane NoisyFloor(FeatureId id, std::mt19937_64* rng) {
  std::normal_distribution<double> edge(0.0, 0.03), height(0.0, 0.005);
  return Rect(id, 0.1 + edge(*rng), 0.1 + edge(*rng), 9.9 + edge(*rng), 5.9 + edge(*rng),
              height(*rng));
}

TEST(PlaneFusionEngineTest, RevisitedFloorKeepsBoundedNodes) {
  PlaneFusionEngine engine({});
  std::mt19937_64 rng(3);
  // First the whole room, then many partial views inside it.
  for (ObservationId o = 1; o <= 400; ++o) {
    MapPlane p = NoisyFloor(o << 8, &rng);
    if (o > 40)
      p = Rect(o << 8, 1 + static_cast<double>(o % 5), 1, 4 + static_cast<double>(o % 5), 4, 0.002);
    ASSERT_TRUE(engine.Add(o, o % 3, {p}).ok());
  }
  EXPECT_EQ(engine.plane_count(), 400u);
  EXPECT_LE(engine.node_count(), 60u);
  ASSERT_EQ(engine.published_count(), 1u);
  const FusedPlane f = engine.Published()[0];
  EXPECT_EQ(f.member_count, 400u);
  EXPECT_GE(f.support, kPlaneEstablishedSupport);
  EXPECT_NEAR(f.area_m2, 60.0, 2.0);
}

TEST(PlaneFusionEngineTest, AHugePlaneCostsNoMemoryByItsAreaAndStillLinks) {
  PlaneFusionEngine engine({});
  // 100 km across: filed apart from the grid, scanned by every query.
  ASSERT_TRUE(engine.Add(1, 1, {Rect(1 << 8, -5e4, -5e4, 5e4, 5e4, 0.0)}).ok());
  ASSERT_TRUE(engine.Add(2, 1, {Rect(2 << 8, 0, 0, 4, 4, 0.01)}).ok());
  ASSERT_TRUE(engine.Add(3, 1, {Rect(3 << 8, 100, 100, 104, 104, 0.02)}).ok());
  ASSERT_TRUE(engine.Add(4, 1, {Rect(4 << 8, 0, 0, 4, 4, 3.0)}).ok());  // a ceiling: apart
  EXPECT_EQ(engine.cluster_count(), 2u);
  ASSERT_EQ(engine.published_count(), 1u);
  EXPECT_EQ(engine.Published()[0].support, 3u);
  std::string state;
  ASSERT_TRUE(engine.SaveState(&state).ok());
  EXPECT_TRUE(PlaneFusionEngine::LoadState({}, state).ok());
}

TEST(PlaneFusionEngineTest, SnapshotRoundTripContinuesBitForBit) {
  PlaneFusionEngine live({});
  std::mt19937_64 rng(5);
  const auto obs = SmallSite();
  for (size_t i = 0; i < obs.size(); ++i) ASSERT_TRUE(live.Add(i + 1, i % 2, obs[i]).ok());
  for (ObservationId o = 100; o < 150; ++o)
    ASSERT_TRUE(live.Add(o, 1, {NoisyFloor(o << 8, &rng)}).ok());
  std::string state;
  ASSERT_TRUE(live.SaveState(&state).ok());
  StatusOr<std::unique_ptr<PlaneFusionEngine>> loaded = PlaneFusionEngine::LoadState({}, state);
  ASSERT_TRUE(loaded.ok()) << loaded.status().ToString();
  PlaneFusionEngine& restored = **loaded;
  std::string again;
  ASSERT_TRUE(restored.SaveState(&again).ok());
  EXPECT_EQ(again, state);
  std::mt19937_64 rng_a(9), rng_b(9);
  for (ObservationId o = 150; o < 200; ++o) {
    ASSERT_TRUE(live.Add(o, 2, {NoisyFloor(o << 8, &rng_a)}).ok());
    ASSERT_TRUE(restored.Add(o, 2, {NoisyFloor(o << 8, &rng_b)}).ok());
  }
  const auto a = live.Published(), b = restored.Published();
  ASSERT_EQ(a.size(), b.size());
  for (size_t k = 0; k < a.size(); ++k) {
    EXPECT_EQ(a[k].id, b[k].id);
    EXPECT_EQ(a[k].support, b[k].support);
    EXPECT_EQ(a[k].normal, b[k].normal);  // bit for bit
    EXPECT_EQ(a[k].offset_m, b[k].offset_m);
    EXPECT_EQ(a[k].boundary, b[k].boundary);
  }
  EXPECT_EQ(live.node_count(), restored.node_count());

  std::string corrupt = state;
  corrupt[corrupt.size() / 2] ^= 0x40;
  EXPECT_NE(PlaneFusionEngine::LoadState({}, corrupt).status().message().find("checksum"),
            std::string::npos);
  EXPECT_FALSE(PlaneFusionEngine::LoadState({}, state.substr(0, 20)).ok());
  PlaneFusionParams other;
  other.max_gap_m = 0.5;
  EXPECT_EQ(PlaneFusionEngine::LoadState(other, state).status().code(),
            StatusCode::kFailedPrecondition);
}

TEST(PlaneGeometryTest, ConvexIntersectionAndGap) {
  using geometry::Vec2;
  const std::vector<Vec2> a = {{0, 0}, {2, 0}, {2, 2}, {0, 2}};
  const std::vector<Vec2> b = {{1, 1}, {3, 1}, {3, 3}, {1, 3}};
  const std::vector<Vec2> c = {{2.5, 0}, {4, 0}, {4, 2}, {2.5, 2}};
  EXPECT_NEAR(ConvexIntersectionArea(a, b), 1.0, 1e-12);
  EXPECT_NEAR(ConvexIntersectionArea(a, c), 0.0, 1e-12);
  EXPECT_NEAR(ConvexPolygonGap(a, b), 0.0, 1e-12);
  EXPECT_NEAR(ConvexPolygonGap(a, c), 0.5, 1e-12);
  EXPECT_NEAR(NormalAngle(Vector3d(0, 0, 1), Vector3d(0, 0, -1)), 0.0, 1e-12);
  EXPECT_EQ(CanonicalNormal(Vector3d(0, 0, -1)), Vector3d(0, 0, 1));
}

}  // namespace
}  // namespace mapd::fusion
