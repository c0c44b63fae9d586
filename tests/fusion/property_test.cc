// The incremental engine against the plain batch reference (batch_reference.h)
// on seeded random scenes, in shuffled arrival orders (docs/algorithms.md A.4,
// "The incremental engine"), with the chain guard off and on, on scenes of rooms and
// on scenes that add curved walls seen as arcs of short chords. Exact mode must
// equal the reference; bounded mode (A.5, the default) on the same scenes
// revisited until clusters are established and fold, and both modes on street
// scenes fed with sensor origins (free-space evidence, A.11), keep what A.5
// promises (see "Bounded mode" below).
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <map>
#include <random>
#include <set>
#include <string>
#include <tuple>

#include "fusion/batch_reference.h"
#include "fusion/criteria.h"
#include "fusion/engine.h"
#include "fusion/engine_inspector.h"

namespace mapd::fusion {

// gtest prints parameters with this (not as bytes).
void PrintTo(CornerPairing pairing, std::ostream* out) { *out << CornerPairingName(pairing); }

namespace {

using geometry::Segment2;
using geometry::Vec2;
using testing::BatchCluster;
using testing::BatchFuse;
using testing::BatchObservation;
using testing::BatchResult;

constexpr double kToleranceM = 1e-9;

struct Scene {
  FusionParams params;
  std::vector<BatchObservation> observations;
};

struct Arc {
  Vec2 centre;
  double radius_m;
  double start_rad;
  double span_rad;
};

// Two draws for one point, y first: the order in which GCC evaluated the
// unsequenced Vec2(draw(), draw()) these scenes were made with, spelled out
// so that every compiler builds the same scene from a seed (clang evaluates
// arguments left to right, and its seed-12 scene had no corner).
template <typename Draw>
Vec2 DrawVec2(Draw&& draw) {
  const double y = draw();
  const double x = draw();
  return Vec2(x, y);
}

// Walls of a few rotated rectangular rooms (corners), some near-parallel walls
// close to others, some free walls; each observation sees a random subset of
// walls as partial, noisy segments. With `curved`, also a few curved walls:
// each sighting covers part of the arc with chords of about 0.5 m whose phase
// differs from sighting to sighting, so that they chain along the arc.
// With `revisits` > 0 that many observations follow which see the walls
// again through a few fixed windows (see below), for bounded mode.
Scene MakeScene(uint32_t seed, bool curved, bool guard,
                CornerPairing pairing = CornerPairing::kMutualNearest,
                FusionMode mode = FusionMode::kExact, int revisits = 0) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::normal_distribution<double> noise(0.0, 0.02);
  const auto uniform = [&](double lo, double hi) { return lo + (hi - lo) * unit(rng); };
  const auto in_square = [&](double half_m) {
    return DrawVec2([&] { return uniform(-half_m, half_m); });
  };
  const auto noise_vec = [&] { return DrawVec2([&] { return noise(rng); }); };

  std::vector<Segment2> walls;
  for (int room = 0; room < 3; ++room) {
    const Vec2 origin = in_square(30);
    const double yaw = uniform(0, M_PI);
    const Vec2 ex(std::cos(yaw), std::sin(yaw));
    const Vec2 ey(-ex.y(), ex.x());
    const double w = uniform(4, 12), h = uniform(4, 12);
    const Vec2 c[4] = {origin, origin + w * ex, origin + w * ex + h * ey, origin + h * ey};
    for (int k = 0; k < 4; ++k) walls.push_back({c[k], c[(k + 1) % 4]});
  }
  for (int k = 0; k < 3; ++k) {  // near-parallel neighbours of existing walls
    const Segment2 base = walls[static_cast<size_t>(k * 3)];
    const Vec2 normal = Vec2(-base.direction().y(), base.direction().x()).normalized();
    const double offset_m = uniform(0.3, 0.8);
    const double tilt = uniform(-0.05, 0.05);
    const Eigen::Rotation2Dd rot(tilt);
    const Vec2 mid = base.midpoint() + offset_m * normal;
    const Vec2 half = rot * (0.4 * base.direction());
    walls.push_back({mid - half, mid + half});
  }
  for (int k = 0; k < 8; ++k) {
    const Vec2 a = in_square(35);
    const double yaw = uniform(0, 2 * M_PI);
    walls.push_back({a, a + uniform(1, 8) * Vec2(std::cos(yaw), std::sin(yaw))});
  }
  std::vector<Arc> arcs;
  for (int k = 0; curved && k < 3; ++k) {
    const Vec2 centre = in_square(35);  // a braced list is evaluated left to right
    arcs.push_back({centre, uniform(3, 10), uniform(0, 2 * M_PI), uniform(M_PI / 3, M_PI)});
  }

  Scene scene;
  scene.params.mode = mode;  // the batch reference is what exact mode promises
  scene.params.min_support = 2 + seed % 2;
  scene.params.corner_mode = seed % 3 == 0 ? CornerMode::kMidpoint : CornerMode::kIntersection;
  scene.params.corner_pairing = pairing;
  if (seed % 5 == 4) scene.params.gamma = 0.0;  // criterion 2 off: the search must still be exact
  if (seed % 7 == 3) scene.params.eta_m = 0.6;
  scene.params.chain_max_rms_m = guard ? (seed % 4 == 1 ? 0.03 : 0.05) : 0.0;
  if (seed % 6 == 5) scene.params.chain_max_sse_ratio = 0.8;
  // Settled walls on odd seeds (bounded mode): the reference's geometry then
  // within the tolerance (ExpectBoundedPromisesInOneOrder); even seeds check
  // the exact promise.
  if (seed % 2 == 0) scene.params.refit_tolerance_m = 0.0;
  // Bounded mode's cost caps (params.h) are where it may leave the exact
  // result on purpose; these scenes test everything else, so the caps are
  // out of reach here (the arcs chain up to ~400 representatives) and
  // tested on their own (FusionEngineTest.*Cap*).
  scene.params.max_component_nodes = 1u << 20;

  // Feature ids are a permutation, so id order is unrelated to arrival order.
  const int observation_count = 60;
  std::vector<FeatureId> ids(observation_count * 160);
  for (size_t i = 0; i < ids.size(); ++i) ids[i] = 1000 + i;
  std::shuffle(ids.begin(), ids.end(), rng);
  size_t next_id = 0;
  // Some walls are seen often, some rarely (below min_support: kept, unpublished).
  std::vector<double> visibility;
  for (size_t w = 0; w < walls.size(); ++w) visibility.push_back(uniform(0.03, 0.35));
  for (int o = 0; o < observation_count; ++o) {
    BatchObservation obs;
    obs.id = 500 + static_cast<ObservationId>(o) * 7;
    obs.robot = static_cast<RobotId>(o % 3);
    const auto add = [&](const Vec2& a, const Vec2& b) {
      GroundFeature f;
      f.id = ids[next_id++];
      f.segment = {a, b};
      f.z_min_m = uniform(-0.1, 0.1);
      f.z_max_m = uniform(2.0, 3.0);
      obs.features.push_back(f);
    };
    for (size_t w = 0; w < walls.size(); ++w) {
      if (unit(rng) > visibility[w]) continue;
      const Segment2& wall = walls[w];
      // Partial views, so that members chain along a wall; now and then a
      // badly extracted one (10 cm noise) that may fail the criteria.
      const double t0 = uniform(-0.05, 0.7);
      const double t1 = std::min(1.05, t0 + uniform(0.15, 0.6));
      const double sigma = unit(rng) < 0.1 ? 5.0 : 1.0;
      const Vec2 noise_b = sigma * noise_vec();  // the second argument's, first (as GCC)
      const Vec2 noise_a = sigma * noise_vec();
      add(wall.a + t0 * wall.direction() + noise_a, wall.a + t1 * wall.direction() + noise_b);
    }
    for (const Arc& arc : arcs) {
      if (unit(rng) > 0.3) continue;
      const double step = 0.5 / arc.radius_m;  // chord angle, rad
      const double from = arc.start_rad + uniform(0, 0.5) * arc.span_rad;
      const double to =
          std::min(arc.start_rad + arc.span_rad, from + uniform(0.3, 0.7) * arc.span_rad);
      const auto on_arc = [&](double angle) -> Vec2 {
        return arc.centre + arc.radius_m * Vec2(std::cos(angle), std::sin(angle)) +
               noise_vec() / 2.0;
      };
      for (double angle = from + uniform(0, step); angle + step <= to; angle += step) {
        const Vec2 b = on_arc(angle + step);  // the second argument first (as GCC)
        add(on_arc(angle), b);
      }
    }
    const int clutter = static_cast<int>(rng() % 4);  // small things, mostly seen once
    for (int k = 0; k < clutter; ++k) {
      const Vec2 a = in_square(35);
      const double yaw = uniform(0, 2 * M_PI);
      add(a, a + uniform(0.3, 2.0) * Vec2(std::cos(yaw), std::sin(yaw)));
    }
    scene.observations.push_back(obs);
  }

  // Revisits: robots coming back to the same places see a wall through one of
  // two fixed windows, with a few millimetres of endpoint noise (one view in
  // five a centimetre), and an arc as chords at one of two fixed phases, so
  // that once a cluster is established (32 observations) new views fold into
  // its representatives. Their ids interleave with the first ones', some below
  // all of them, so that a folded feature may name its cluster.
  if (revisits > 0) {
    struct Window {
      double t0, t1;
    };
    std::vector<Window> windows;
    for (size_t w = 0; w < walls.size(); ++w) {
      for (int k = 0; k < 2; ++k) {
        const double t0 = uniform(-0.05, 0.5);
        windows.push_back({t0, std::min(1.05, t0 + uniform(0.4, 0.6))});
      }
    }
    std::vector<FeatureId> more(static_cast<size_t>(revisits) * 60);
    for (size_t i = 0; i < more.size(); ++i) more[i] = i < 900 ? 1 + i : 1000 + ids.size() + i;
    std::shuffle(more.begin(), more.end(), rng);
    size_t next_more = 0;
    for (int o = 0; o < revisits; ++o) {
      BatchObservation obs;
      obs.id = 500 + static_cast<ObservationId>(observation_count + o) * 7;
      obs.robot = static_cast<RobotId>(o % 3);
      const double sigma = unit(rng) < 0.2 ? 0.01 : 0.004;
      std::normal_distribution<double> jitter(0.0, sigma);
      const auto jitter_vec = [&] { return DrawVec2([&] { return jitter(rng); }); };
      const auto add = [&](const Vec2& a, const Vec2& b) {
        GroundFeature f;
        f.id = more[next_more++];
        f.segment = {a + jitter_vec(), b + jitter_vec()};
        f.z_max_m = 2.5;
        obs.features.push_back(f);
      };
      for (size_t w = 0; w < walls.size(); ++w) {
        if (unit(rng) > 0.25 + 1.5 * visibility[w]) continue;
        const Window& window = windows[2 * w + rng() % 2];
        add(walls[w].a + window.t0 * walls[w].direction(),
            walls[w].a + window.t1 * walls[w].direction());
      }
      for (const Arc& arc : arcs) {  // 3 m of the arc's middle
        if (unit(rng) > 0.5) continue;
        const double step = 0.5 / arc.radius_m;
        const double from = arc.start_rad + 0.5 * arc.span_rad + (rng() % 2) * 0.5 * step;
        const auto on_arc = [&](double angle) -> Vec2 {
          return arc.centre + arc.radius_m * Vec2(std::cos(angle), std::sin(angle));
        };
        for (int k = 0; k < 6; ++k) add(on_arc(from + k * step), on_arc(from + (k + 1) * step));
      }
      scene.observations.push_back(obs);
    }
  }
  return scene;
}

double SegmentDistance(const Segment2& s, const Segment2& t) {
  const double same = std::max((s.a - t.a).norm(), (s.b - t.b).norm());
  const double swapped = std::max((s.a - t.b).norm(), (s.b - t.a).norm());
  return std::min(same, swapped);
}

// Checks that `feed` accounts for every difference between two snapshots.
void ExpectFeedExplains(const std::vector<FusedFeature>& before,
                        const std::vector<FusedFeature>& after, const ChangeFeed& feed) {
  std::map<ClusterId, const FusedFeature*> old_by_id, new_by_id;
  for (const FusedFeature& f : before) old_by_id[f.id] = &f;
  for (const FusedFeature& f : after) new_by_id[f.id] = &f;
  const std::set<ClusterId> added(feed.added.begin(), feed.added.end());
  const std::set<ClusterId> updated(feed.updated.begin(), feed.updated.end());
  const std::set<ClusterId> removed(feed.removed.begin(), feed.removed.end());
  for (const auto& [id, f] : new_by_id) {
    auto old = old_by_id.find(id);
    if (old == old_by_id.end()) {
      EXPECT_TRUE(added.count(id)) << id;
      continue;
    }
    const bool changed = old->second->segment.a != f->segment.a ||
                         old->second->segment.b != f->segment.b ||
                         old->second->member_count != f->member_count;
    if (changed) {
      EXPECT_TRUE(updated.count(id)) << id;
    }
  }
  for (const auto& [id, f] : old_by_id) {
    if (!new_by_id.count(id)) {
      EXPECT_TRUE(removed.count(id)) << id;
    }
  }
  // And the feed claims nothing false.
  for (ClusterId id : added) EXPECT_TRUE(!old_by_id.count(id) && new_by_id.count(id)) << id;
  for (ClusterId id : updated) EXPECT_TRUE(old_by_id.count(id) && new_by_id.count(id)) << id;
  for (ClusterId id : removed) EXPECT_TRUE(old_by_id.count(id) && !new_by_id.count(id)) << id;
}

// Bounded mode counts support exactly up to this many observations, and past
// it may overcount but never drop one (support_counter.h; the engine's cap is
// max(32, min_support), and every scene here has min_support <= 3).
constexpr uint32_t kExactSupportUpTo = 32;

// Adds one observation as mapd does: with its sensor origin when it has one
// (free-space evidence, FusionEngine::AddFrom).
Status Feed(FusionEngine* engine, const BatchObservation& obs, ChangeFeed* feed = nullptr) {
  if (obs.has_sensor) {
    return engine->AddFrom(obs.id, obs.robot, obs.sensor_xy_m, obs.features, feed);
  }
  return engine->Add(obs.id, obs.robot, obs.features, feed);
}

std::vector<ClusterId> PublishedIds(const BatchResult& reference) {
  std::vector<ClusterId> ids;
  for (const BatchCluster& w : reference.walls) ids.push_back(w.id);
  return ids;
}

// The engine's map is the reference's: the partition, the cluster count,
// the published ids, and per cluster and wall the support, the member count,
// the fitted and the corner-optimised segment (within geometry_m). With
// `bounded`, the partition compared is the reference's restricted to the
// engine's nodes (its representatives: folded features are members of a
// cluster but no node), and support past kExactSupportUpTo may be larger.
void ExpectSameMap(const FusionEngine& engine, const BatchResult& reference, bool bounded,
                   double geometry_m = kToleranceM) {
  const std::vector<std::vector<FeatureId>> partition = EngineInspector::Partition(engine);
  std::set<FeatureId> nodes;
  for (const std::vector<FeatureId>& cluster : partition)
    nodes.insert(cluster.begin(), cluster.end());
  std::vector<std::vector<FeatureId>> reference_partition;
  for (const BatchCluster& c : reference.clusters) {
    std::vector<FeatureId> members;
    for (FeatureId id : c.members) {
      if (!bounded || nodes.count(id)) members.push_back(id);
    }
    reference_partition.push_back(members);
  }
  std::sort(reference_partition.begin(), reference_partition.end());
  EXPECT_EQ(partition, reference_partition);
  EXPECT_EQ(engine.cluster_count(), reference.clusters.size());
  const std::vector<ClusterId> reference_published = PublishedIds(reference);
  std::vector<ClusterId> published_ids;
  for (const FusedFeature& f : engine.Published()) published_ids.push_back(f.id);
  EXPECT_EQ(published_ids, reference_published);
  // Never two features with the same segment (wall consolidation, rule b).
  const std::vector<FusedFeature> published = engine.Published();
  for (size_t i = 0; i < published.size(); ++i) {
    for (size_t j = i + 1; j < published.size(); ++j) {
      const bool same = (published[i].segment.a == published[j].segment.a &&
                         published[i].segment.b == published[j].segment.b) ||
                        (published[i].segment.a == published[j].segment.b &&
                         published[i].segment.b == published[j].segment.a);
      EXPECT_FALSE(same) << published[i].id << " and " << published[j].id;
    }
  }

  const auto expect_same = [&](const BatchCluster& c) {
    const std::optional<FusedFeature> fused = engine.Get(c.id);
    ASSERT_TRUE(fused.has_value()) << c.id;
    if (bounded && c.support > kExactSupportUpTo) {
      EXPECT_GE(fused->support, c.support) << c.id;
    } else {
      EXPECT_EQ(fused->support, c.support) << c.id;
    }
    EXPECT_EQ(fused->member_count, c.members.size()) << c.id;
    EXPECT_LE(SegmentDistance(fused->fitted, c.fitted), geometry_m) << c.id;
    EXPECT_LE(SegmentDistance(fused->segment, c.segment), geometry_m) << c.id;
  };
  for (const BatchCluster& w : reference.walls) expect_same(w);
  for (const BatchCluster& c : reference.clusters) {
    if (!c.published) {
      expect_same(c);
    } else if (!std::binary_search(reference_published.begin(), reference_published.end(), c.id)) {
      EXPECT_FALSE(engine.Get(c.id).has_value()) << c.id << " is part of a wall";
    }
  }
  // GetPublished (what the server writes from) is Published(), by id.
  for (const FusedFeature& f : published) {
    const std::optional<FusedFeature> p = engine.GetPublished(f.id);
    ASSERT_TRUE(p.has_value()) << f.id;
    EXPECT_EQ(p->segment.a, f.segment.a) << f.id;
    EXPECT_EQ(p->segment.b, f.segment.b) << f.id;
    EXPECT_EQ(p->support, f.support) << f.id;
  }
  for (const BatchCluster& c : reference.clusters) {
    if (!std::binary_search(published_ids.begin(), published_ids.end(), c.id)) {
      EXPECT_FALSE(engine.GetPublished(c.id).has_value()) << c.id;
    }
  }
}

// The arrival orders every scene is fed in: as generated, reversed, and two
// shuffles.
std::vector<std::vector<BatchObservation>> ArrivalOrders(const Scene& scene, uint32_t seed) {
  std::vector<std::vector<BatchObservation>> orders;
  std::mt19937 shuffler(seed * 31 + 1);
  for (int order = 0; order < 4; ++order) {
    std::vector<BatchObservation> arrival = scene.observations;
    if (order == 1) std::reverse(arrival.begin(), arrival.end());
    if (order >= 2) std::shuffle(arrival.begin(), arrival.end(), shuffler);
    orders.push_back(std::move(arrival));
  }
  return orders;
}

// Exact mode (A.4): the reference, in every order, and every Add's change
// feed explains what changed.
void ExpectExactEqualsBatchInEveryOrder(const Scene& scene, const BatchResult& reference,
                                        uint32_t seed) {
  ASSERT_EQ(scene.params.mode, FusionMode::kExact);
  ASSERT_GT(reference.walls.size(), 3u) << "a scene without structure tests little";
  size_t snapped_ends = 0;
  for (const BatchCluster& w : reference.walls) {
    snapped_ends += (w.segment.a != w.fitted.a) + (w.segment.b != w.fitted.b);
  }
  ASSERT_GT(snapped_ends, 0u) << "a scene without corners tests little";

  const std::vector<std::vector<BatchObservation>> orders = ArrivalOrders(scene, seed);
  for (size_t order = 0; order < orders.size(); ++order) {
    SCOPED_TRACE("order " + std::to_string(order));
    FusionEngine engine(scene.params);
    for (const BatchObservation& obs : orders[order]) {
      const std::vector<FusedFeature> before =
          order == 0 ? engine.Published() : std::vector<FusedFeature>();
      ChangeFeed feed;
      const Status added = Feed(&engine, obs, &feed);
      ASSERT_TRUE(added.ok()) << added.ToString();
      if (order == 0) ExpectFeedExplains(before, engine.Published(), feed);
    }
    ExpectSameMap(engine, reference, /*bounded=*/false);
  }
}

// (seed, curved walls, chain guard on, corner pairing).
class PropertyTest
    : public ::testing::TestWithParam<std::tuple<uint32_t, bool, bool, CornerPairing>> {};

TEST_P(PropertyTest, IncrementalEqualsBatchInEveryOrder) {
  const auto [seed, curved, guard, pairing] = GetParam();
  const Scene scene = MakeScene(seed, curved, guard, pairing);
  const BatchResult reference = BatchFuse(scene.observations, scene.params);
  if (curved && guard) {
    // The guard must have something to do: it cuts at least one component.
    FusionParams off = scene.params;
    off.chain_max_rms_m = 0.0;
    ASSERT_GT(reference.clusters.size(), BatchFuse(scene.observations, off).clusters.size());
  }
  ExpectExactEqualsBatchInEveryOrder(scene, reference, seed);
}

// ---- Bounded mode ------------------------------------------------------------
//
// What bounded mode promises against the reference (docs/algorithms.md A.5,
// A.6, A.9; engine.cc: FindCover, Add, LinkToEarlier), and what
// ExpectBoundedKeepsItsPromises checks in every arrival order:
//  1. A feature folds only into a representative of an ESTABLISHED cluster
//     (a component seen by >= 32 observations). Until its first fold the
//     engine has one node per feature and is the exact engine: its map is
//     the reference's for the observations so far (support past 32 aside,
//     see 3); and those observations already hold a component of >= 32.
//  2. A folded feature lies within cover_m of a representative at both ends
//     (Eq. 15), that representative arrived before it, and the two meet the
//     three criteria.
//  3. Only representatives search for links and every link meets the
//     criteria, so the engine's components are those of the criteria graph
//     over its representatives (a feature folded into r stands for r); the
//     chain guard cuts between representatives, each weighted with what was
//     folded into it. So bounded may differ from exact in two known ways:
//     folding dropped a link only the folded feature had (a borderline
//     pair), or the reference's guard cuts between a folded feature and its
//     representative. Where neither happened - the reference's clusters
//     restricted to the representatives are the engine's, and every
//     representative that covers a folded feature lies in that feature's
//     reference cluster - the map is the reference's: the same published
//     ids, member counts (folded features included), fitted and
//     corner-optimised segments within 1e-9 m, walls (consolidation and its
//     free-space evidence are functions of the pieces and the views, and
//     every view counts, folded or not), and support equal up to 32 and
//     never smaller past it (A.6). Where one did, the engine's clusters are
//     still those components (guard off) or lie within them (guard on).
// The scenes fold a good share of their features (asserted), so that 2 and 3
// are not vacuous, and each must have the reference's map in at least one order.

// The arrival index of each feature's observation.
std::map<FeatureId, size_t> ArrivalIndex(const std::vector<BatchObservation>& arrival) {
  std::map<FeatureId, size_t> index;
  for (size_t k = 0; k < arrival.size(); ++k) {
    for (const GroundFeature& f : arrival[k].features) index[f.id] = k;
  }
  return index;
}

// The larger of the two endpoint distances in the pairing that makes it smaller (Eq. 15).
double CoverDistance(const Segment2& f, const Segment2& r) { return SegmentDistance(f, r); }

// Returns whether the engine's clusters matched the reference's (promise 3's
// condition), after checking promises 1-3.
// `folded_share`: the share of the features folded.
bool ExpectBoundedPromisesInOneOrder(const Scene& scene, const BatchResult& reference,
                                     const std::vector<BatchObservation>& arrival,
                                     double* folded_share) {
  FusionEngine engine(scene.params);
  size_t first_fold = arrival.size();
  for (size_t k = 0; k < arrival.size(); ++k) {
    const size_t nodes_before = engine.node_count();
    const Status added = Feed(&engine, arrival[k]);
    EXPECT_TRUE(added.ok()) << added.ToString();
    if (first_fold == arrival.size() &&
        engine.node_count() - nodes_before < arrival[k].features.size()) {
      first_fold = k;
    }
  }
  const size_t folded = engine.feature_count() - engine.node_count();
  *folded_share = static_cast<double>(folded) / static_cast<double>(engine.feature_count());
  EXPECT_GT(folded, engine.feature_count() / 5)
      << "bounded mode is about folding: a scene that folds little tests little";
  EXPECT_LT(first_fold, arrival.size());
  if (first_fold == arrival.size()) return false;

  // 1. Until the first fold: the exact engine, on a component of >= 32 observations.
  {
    SCOPED_TRACE("the observations before the first fold");
    const std::vector<BatchObservation> young(arrival.begin(),
                                              arrival.begin() + static_cast<long>(first_fold));
    FusionEngine before(scene.params);
    for (const BatchObservation& obs : young) EXPECT_TRUE(Feed(&before, obs).ok());
    EXPECT_EQ(before.node_count(), before.feature_count());
    ExpectSameMap(before, BatchFuse(young, scene.params), /*bounded=*/true);
    FusionParams components = scene.params;  // the reference's clusters are then components
    components.chain_max_rms_m = 0.0;
    components.consolidate = false;
    uint32_t most_seen = 0;
    for (const BatchCluster& c : BatchFuse(young, components).clusters) {
      most_seen = std::max(most_seen, c.support);
    }
    EXPECT_GE(most_seen, kExactSupportUpTo) << "a fold before any cluster was established";
  }

  // 2. Every folded feature is covered by an earlier representative.
  const std::vector<std::vector<FeatureId>> partition = EngineInspector::Partition(engine);
  std::set<FeatureId> nodes;
  for (const std::vector<FeatureId>& cluster : partition)
    nodes.insert(cluster.begin(), cluster.end());
  EXPECT_EQ(nodes.size(), engine.node_count());
  const std::map<FeatureId, size_t> arrived = ArrivalIndex(arrival);
  std::vector<std::pair<double, const GroundFeature*>> representatives;  // by midpoint x
  std::vector<const GroundFeature*> folded_features;
  for (const BatchObservation& obs : arrival) {
    for (const GroundFeature& f : obs.features) {
      if (nodes.count(f.id)) {
        representatives.push_back({f.segment.midpoint().x(), &f});
      } else {
        folded_features.push_back(&f);
      }
    }
  }
  EXPECT_EQ(folded_features.size(), folded);
  std::sort(representatives.begin(), representatives.end(),
            [](const auto& x, const auto& y) { return x.first < y.first; });
  const double cover_m = scene.params.cover_m;
  // Per folded feature, every representative that could have taken it.
  std::map<FeatureId, std::vector<FeatureId>> covers;
  size_t uncovered = 0;
  for (const GroundFeature* f : folded_features) {
    // Both ends within cover_m puts the midpoints within cover_m too.
    const double x = f->segment.midpoint().x();
    auto r = std::lower_bound(representatives.begin(), representatives.end(), x - cover_m,
                              [](const auto& item, double v) { return item.first < v; });
    std::vector<FeatureId>& by = covers[f->id];
    for (; r != representatives.end() && r->first <= x + cover_m; ++r) {
      if (arrived.at(r->second->id) < arrived.at(f->id) &&
          CoverDistance(f->segment, r->second->segment) <= cover_m &&
          MeetsAllCriteria(f->segment, r->second->segment, scene.params)) {
        by.push_back(r->second->id);
      }
    }
    if (by.empty() && ++uncovered <= 3) {
      ADD_FAILURE() << "feature " << f->id << " was folded but no earlier representative covers it";
    }
  }
  EXPECT_EQ(uncovered, 0u);

  // 3. The reference's clusters restricted to the representatives, and
  // whether every folded feature's covering representatives lie in its own
  // reference cluster (else the guard, which cuts between representatives,
  // may keep it with one the reference's cut put elsewhere).
  std::vector<std::vector<FeatureId>> restricted;
  std::map<FeatureId, size_t> reference_cluster_of;
  for (size_t c = 0; c < reference.clusters.size(); ++c) {
    std::vector<FeatureId> members;
    for (FeatureId id : reference.clusters[c].members) {
      reference_cluster_of[id] = c;
      if (nodes.count(id)) members.push_back(id);
    }
    restricted.push_back(members);
  }
  std::sort(restricted.begin(), restricted.end());
  bool folded_where_the_reference_has_them = true;
  for (const auto& [id, by] : covers) {
    for (FeatureId r : by) {
      folded_where_the_reference_has_them &=
          reference_cluster_of.at(r) == reference_cluster_of.at(id);
    }
  }
  if (partition == restricted && folded_where_the_reference_has_them) {
    // Settled walls keep the fit they were last consolidated with, within
    // refit_tolerance_m of the exact refit at each end; a wall of several
    // pieces and its corners may move by a little more.
    ExpectSameMap(engine, reference, /*bounded=*/true,
                  kToleranceM + 2.0 * scene.params.refit_tolerance_m);
    return true;
  }
  std::vector<BatchObservation> only_nodes = arrival;
  for (BatchObservation& obs : only_nodes) {
    obs.features.erase(std::remove_if(obs.features.begin(), obs.features.end(),
                                      [&](const GroundFeature& f) { return !nodes.count(f.id); }),
                       obs.features.end());
  }
  FusionParams components = scene.params;
  components.chain_max_rms_m = 0.0;
  components.consolidate = false;
  std::map<FeatureId, size_t> component_of;
  const BatchResult graph = BatchFuse(only_nodes, components);
  for (size_t c = 0; c < graph.clusters.size(); ++c) {
    for (FeatureId id : graph.clusters[c].members) component_of[id] = c;
  }
  if (scene.params.chain_max_rms_m == 0.0) {
    std::vector<std::vector<FeatureId>> expected;
    for (const BatchCluster& c : graph.clusters) expected.push_back(c.members);
    std::sort(expected.begin(), expected.end());
    EXPECT_EQ(partition, expected);
  } else {
    for (const std::vector<FeatureId>& group : partition) {  // the guard's groups of components
      for (FeatureId id : group) EXPECT_EQ(component_of.at(id), component_of.at(group.front()));
    }
  }
  return false;
}

void ExpectBoundedKeepsItsPromises(const Scene& scene, const BatchResult& reference,
                                   uint32_t seed) {
  ASSERT_EQ(scene.params.mode, FusionMode::kBounded);
  ASSERT_GT(reference.walls.size(), 3u) << "a scene without structure tests little";
  const std::vector<std::vector<BatchObservation>> orders = ArrivalOrders(scene, seed);
  size_t same_as_reference = 0;
  double least_folded = 1.0;
  for (size_t order = 0; order < orders.size(); ++order) {
    SCOPED_TRACE("order " + std::to_string(order));
    double folded_share = 0.0;
    same_as_reference +=
        ExpectBoundedPromisesInOneOrder(scene, reference, orders[order], &folded_share);
    least_folded = std::min(least_folded, folded_share);
  }
  std::printf(
      "bounded mode folded >= %.0f %% of the features, had the reference's clusters in "
      "%zu of %zu orders\n",
      100.0 * least_folded, same_as_reference, orders.size());
  EXPECT_GT(same_as_reference, 0u) << "never the reference's clusters: promise 3 went unchecked";
}

// (seed, curved walls, chain guard on): the property test's scenes, revisited.
class BoundedPropertyTest : public ::testing::TestWithParam<std::tuple<uint32_t, bool, bool>> {};

TEST_P(BoundedPropertyTest, KeepsWhatBoundedModePromisesInEveryOrder) {
  const auto [seed, curved, guard] = GetParam();
  const Scene scene = MakeScene(seed, curved, guard, CornerPairing::kMutualNearest,
                                FusionMode::kBounded, /*revisits=*/100);
  ExpectBoundedKeepsItsPromises(scene, BatchFuse(scene.observations, scene.params), seed);
}

// ---- Free-space evidence -----------------------------------------------------

// An interval [lo, hi] along a line.
struct Span {
  double lo, hi;
};

// `span` less `shadow`: up to two spans.
std::vector<Span> Minus(const Span& span, const Span& shadow) {
  if (shadow.hi <= span.lo || shadow.lo >= span.hi) return {span};
  std::vector<Span> out;
  if (shadow.lo > span.lo) out.push_back({span.lo, shadow.lo});
  if (shadow.hi < span.hi) out.push_back({shadow.hi, span.hi});
  return out;
}

// A street, fed as mapd feeds it: every observation with its sensor origin
// (docs/algorithms.md A.11, "Free-space evidence"). In a frame of its own
// (rotated and moved by the seed): a front wall y = 0, x in [0, 32], with a
// door that the sensors see through to a back wall behind it, and a stretch
// hidden from them by a fence (y = -2.5) that nothing sees through; end walls
// x = 0 and x = 32 from y = -10 (two corners). The sensors stand at y in
// [-8, -6]: most at one of six stations they come back to
// (millimetre noise, one in five a centimetre: bounded mode folds these),
// the others anywhere (1.5 cm). Each reports what it sees within its field
// of view: the front wall's pieces less the fence's shadow, the fence, an end
// wall, and the part of the back wall seen through the door. On odd seeds a
// few also report a phantom segment across the door (a glass pane seen at a
// grazing angle): a piece that the door's seen-free cells pierce. Evidence
// then decides three things the plain relation does not: the pieces either
// side of the fence's stretch join (nothing seen through it), those either
// side of the door do not (seen through), and the phantom joins nothing.
Scene MakeStreet(uint32_t seed, FusionMode mode, bool guard) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const auto uniform = [&](double lo, double hi) { return lo + (hi - lo) * unit(rng); };
  const double yaw = uniform(0, 2 * M_PI);
  const Eigen::Rotation2Dd rotation(yaw);
  const double shift_x = uniform(-50, 50);  // not as two arguments: their order is unspecified
  const Vec2 shift(shift_x, uniform(-50, 50));
  const auto world = [&](double x, double y) -> Vec2 { return shift + rotation * Vec2(x, y); };

  constexpr double kWidthM = 32.0, kFenceY = -2.5;
  const double door = uniform(7, 9), door_width = uniform(2.0, 3.0);
  const double hidden = uniform(19, 21), hidden_width = uniform(2.0, 4.0);
  const Span fence{hidden - 1.0, hidden + hidden_width + 1.0};
  const double back_y = uniform(4, 6);
  const Span back{door - 8.0, door + door_width + 8.0};
  const std::vector<Span> front = {
      {0.0, door}, {door + door_width, hidden}, {hidden + hidden_width, kWidthM}};
  struct Station {
    Vec2 at;
    double reach_m;  // half the field of view along the wall
  };
  std::vector<Station> stations;
  for (int k = 0; k < 6; ++k) {
    const double x = 2.0 + k * (kWidthM - 4.0) / 5.0 + uniform(-1, 1);
    const double y = uniform(-8, -6);
    stations.push_back({Vec2(x, y), uniform(5, 8)});
  }
  const size_t door_station = door < 5.0 ? 0 : door < 10.0 ? 1 : 2;

  Scene scene;
  scene.params.mode = mode;
  scene.params.min_support = 2 + seed % 2;
  scene.params.corner_mode = seed % 3 == 0 ? CornerMode::kMidpoint : CornerMode::kIntersection;
  scene.params.chain_max_rms_m = guard ? 0.05 : 0.0;
  // Retirement depends on the order of observations by design (what was seen
  // through after the last support): the batch reference has no order, so
  // these scenes leave it off (wall_retirement_test.cc tests it; with it on,
  // the odd seeds' phantom across the door is retired once seen through).
  scene.params.retire_views = 0;
  if (seed % 2 == 0) scene.params.refit_tolerance_m = 0.0;  // as MakeScene

  constexpr int kObservations = 160;
  std::vector<FeatureId> ids(kObservations * 10);
  for (size_t i = 0; i < ids.size(); ++i) ids[i] = 1 + i;
  std::shuffle(ids.begin(), ids.end(), rng);
  size_t next_id = 0;
  int phantoms = 0;
  for (int o = 0; o < kObservations; ++o) {
    const bool at_station = unit(rng) < 0.85;
    const size_t station = rng() % stations.size();
    Station from = stations[station];
    double sigma = unit(rng) < 0.2 ? 0.01 : 0.003;
    if (!at_station) {
      const double x = uniform(2, kWidthM - 2);
      const double y = uniform(-9, -5);
      from = {Vec2(x, y), uniform(4, 9)};
      sigma = 0.015;
    }
    std::normal_distribution<double> noise(0.0, sigma);
    BatchObservation obs;
    obs.id = 100 + static_cast<ObservationId>(o) * 3;
    obs.robot = static_cast<RobotId>(o % 4);
    obs.has_sensor = true;
    obs.sensor_xy_m = world(from.at.x(), from.at.y());
    const auto add = [&](double ax, double ay, double bx, double by) {
      GroundFeature f;
      f.id = ids[next_id++];
      const double nax = noise(rng), nay = noise(rng), nbx = noise(rng), nby = noise(rng);
      f.segment = {world(ax + nax, ay + nay), world(bx + nbx, by + nby)};
      f.z_max_m = 2.5;
      obs.features.push_back(f);
    };
    // A span of the line y, if long enough for a line extractor.
    const auto add_span = [&](const Span& span, double y) {
      if (span.hi - span.lo >= 0.6) add(span.lo, y, span.hi, y);
    };
    const Vec2 o_xy = from.at;
    const Span view{o_xy.x() - from.reach_m, o_xy.x() + from.reach_m};
    // The fence's shadow on y = 0, seen from o_xy.
    const double to_fence = (0.0 - o_xy.y()) / (kFenceY - o_xy.y());
    const Span shadow{o_xy.x() + (fence.lo - o_xy.x()) * to_fence,
                      o_xy.x() + (fence.hi - o_xy.x()) * to_fence};
    for (const Span& piece : front) {
      const Span seen{std::max(piece.lo, view.lo), std::min(piece.hi, view.hi)};
      if (seen.hi <= seen.lo) continue;
      for (const Span& part : Minus(seen, shadow)) add_span(part, 0.0);
    }
    add_span({std::max(fence.lo, view.lo), std::min(fence.hi, view.hi)}, kFenceY);
    if (view.lo <= 0.0) add(0.0, -10.0, 0.0, 0.0);
    if (view.hi >= kWidthM) add(kWidthM, -10.0, kWidthM, 0.0);
    if (view.lo < door + door_width && view.hi > door) {
      // Through the door, 5 cm inside its jambs.
      const double to_back = (back_y - o_xy.y()) / (0.0 - o_xy.y());
      const double lo = o_xy.x() + (door + 0.05 - o_xy.x()) * to_back;
      const double hi = o_xy.x() + (door + door_width - 0.05 - o_xy.x()) * to_back;
      add_span({std::max(lo, back.lo), std::min(hi, back.hi)}, back_y);
    }
    if (seed % 2 == 1 && at_station && station == door_station && phantoms < 4) {
      ++phantoms;
      add_span({door - 0.4, door + door_width + 0.4}, 0.01);
    }
    scene.observations.push_back(obs);
  }
  return scene;
}

// The same observations without their sensor origins: no evidence.
std::vector<BatchObservation> WithoutSensors(std::vector<BatchObservation> observations) {
  for (BatchObservation& obs : observations) obs.has_sensor = false;
  return observations;
}

// The evidence decides something in every street: an occluded gap joined, a
// gap seen through kept apart, and (odd seeds) a pierced phantom; the walls
// with it differ from the walls without it.
void ExpectEvidenceMatters(const Scene& scene, const BatchResult& reference, uint32_t seed) {
  ASSERT_TRUE(reference.evidence.on);
  EXPECT_GT(reference.evidence.free_cells, 50u);
  EXPECT_GT(reference.evidence.occluded_joins, 0u) << "no gap joined for lack of sight lines";
  EXPECT_GT(reference.evidence.seen_free_vetoes, 0u) << "no gap kept apart by sight lines";
  if (seed % 2 == 1) {
    EXPECT_GT(reference.evidence.pierced, 0u) << "the phantom across the door was not pierced";
  }
  const BatchResult blind = BatchFuse(WithoutSensors(scene.observations), scene.params);
  EXPECT_FALSE(blind.evidence.on);
  EXPECT_NE(PublishedIds(reference), PublishedIds(blind)) << "the evidence changed no wall";
}

// (seed, chain guard on).
class StreetPropertyTest : public ::testing::TestWithParam<std::tuple<uint32_t, bool>> {};

TEST_P(StreetPropertyTest, ExactWithEvidenceEqualsBatchInEveryOrder) {
  const auto [seed, guard] = GetParam();
  const Scene scene = MakeStreet(seed, FusionMode::kExact, guard);
  const BatchResult reference = BatchFuse(scene.observations, scene.params);
  ExpectEvidenceMatters(scene, reference, seed);
  ExpectExactEqualsBatchInEveryOrder(scene, reference, seed);
}

TEST_P(StreetPropertyTest, BoundedWithEvidenceKeepsItsPromisesInEveryOrder) {
  const auto [seed, guard] = GetParam();
  const Scene scene = MakeStreet(seed, FusionMode::kBounded, guard);
  const BatchResult reference = BatchFuse(scene.observations, scene.params);
  ExpectEvidenceMatters(scene, reference, seed);
  ExpectBoundedKeepsItsPromises(scene, reference, seed);
}

// The scenes exercise consolidation: in some, walls hold several published clusters.
TEST(PropertyScenes, ConsolidationJoinsClustersInSomeScenes) {
  size_t joined = 0;
  for (uint32_t seed = 1; seed < 25; ++seed) {
    const BatchResult r =
        BatchFuse(MakeScene(seed, false, true).observations, MakeScene(seed, false, true).params);
    size_t published = 0;
    for (const BatchCluster& c : r.clusters) published += c.published;
    joined += published - r.walls.size();
  }
  std::printf("published clusters joined into walls over 24 scenes: %zu\n", joined);
  EXPECT_GT(joined, 0u);
}

// The scenes exercise the pairing: in some, greedy and mutual nearest differ
// (with curved walls: their chords put many endpoints close together).
TEST(PropertyScenes, GreedyPairingDiffersInSomeScenes) {
  size_t differ = 0;
  for (uint32_t seed = 1; seed < 13; ++seed) {  // the seeds of the Greedy instantiation
    const Scene mutual = MakeScene(seed, true, true, CornerPairing::kMutualNearest);
    const Scene greedy = MakeScene(seed, true, true, CornerPairing::kGreedy);
    const BatchResult m = BatchFuse(mutual.observations, mutual.params);
    const BatchResult g = BatchFuse(greedy.observations, greedy.params);
    ASSERT_EQ(m.walls.size(), g.walls.size());
    for (size_t k = 0; k < m.walls.size(); ++k) {
      differ += (m.walls[k].segment.a != g.walls[k].segment.a) +
                (m.walls[k].segment.b != g.walls[k].segment.b);
    }
  }
  std::printf("endpoints snapped differently by greedy over 12 curved scenes: %zu\n", differ);
  EXPECT_GT(differ, 0u);
}

// Test names read "seed3_curved_guard_mutual".
std::string PropertyCaseName(const ::testing::TestParamInfo<PropertyTest::ParamType>& info) {
  const auto& [seed, curved, guard, pairing] = info.param;
  return "seed" + std::to_string(seed) + (curved ? "_curved" : "_straight") +
         (guard ? "_guard" : "_noguard") + "_" + CornerPairingName(pairing);
}

INSTANTIATE_TEST_SUITE_P(Seeds, PropertyTest,
                         ::testing::Combine(::testing::Range(1u, 25u), ::testing::Bool(),
                                            ::testing::Bool(),
                                            ::testing::Values(CornerPairing::kMutualNearest)),
                         PropertyCaseName);
// Greedy on half the seeds: ctest time.
INSTANTIATE_TEST_SUITE_P(Greedy, PropertyTest,
                         ::testing::Combine(::testing::Range(1u, 13u), ::testing::Bool(),
                                            ::testing::Bool(),
                                            ::testing::Values(CornerPairing::kGreedy)),
                         PropertyCaseName);

std::string BoundedCaseName(const ::testing::TestParamInfo<BoundedPropertyTest::ParamType>& info) {
  const auto& [seed, curved, guard] = info.param;
  return "seed" + std::to_string(seed) + (curved ? "_curved" : "_straight") +
         (guard ? "_guard" : "_noguard");
}

// Bounded mode on the first 6 seeds' scenes, revisited, and with curved walls
// on the first 2 (a curved scene costs as much as eight straight ones: ctest
// time). Not every seed's curved scene would do: with the guard on, seed 5's
// cut falls between a folded chord and its representative in every order, so
// no order has the reference's clusters and only promises 1, 2 and the
// components of 3 are checked there.
INSTANTIATE_TEST_SUITE_P(Straight, BoundedPropertyTest,
                         ::testing::Combine(::testing::Range(1u, 7u), ::testing::Values(false),
                                            ::testing::Bool()),
                         BoundedCaseName);
INSTANTIATE_TEST_SUITE_P(Curved, BoundedPropertyTest,
                         ::testing::Combine(::testing::Range(1u, 3u), ::testing::Values(true),
                                            ::testing::Bool()),
                         BoundedCaseName);

std::string StreetCaseName(const ::testing::TestParamInfo<StreetPropertyTest::ParamType>& info) {
  const auto& [seed, guard] = info.param;
  return "seed" + std::to_string(seed) + (guard ? "_guard" : "_noguard");
}

INSTANTIATE_TEST_SUITE_P(Seeds, StreetPropertyTest,
                         ::testing::Combine(::testing::Range(1u, 7u), ::testing::Bool()),
                         StreetCaseName);

}  // namespace
}  // namespace mapd::fusion
