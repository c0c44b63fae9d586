// ClusterStats::MergeAll (one hull for a whole wall) against merging the
// parts one by one, as walls were merged before it.
#include "fusion/cluster_stats.h"

#include <gtest/gtest.h>

#include <random>
#include <vector>

namespace mapd::fusion {
namespace {

using geometry::Vec2;

ClusterStats RandomCluster(std::mt19937& rng, FeatureId first_id, ObservationId first_obs) {
  std::uniform_real_distribution<double> coord(-5.0, 5.0), noise(-0.05, 0.05);
  const int members = 1 + static_cast<int>(rng() % 12);
  ClusterStats stats;
  for (int k = 0; k < members; ++k) {
    GroundFeature f;
    f.id = first_id + static_cast<FeatureId>(k);
    const double x0 = coord(rng), x1 = coord(rng);
    f.segment = {Vec2(x0, 0.3 * x0 + noise(rng)), Vec2(x1 + 0.1, 0.3 * x1 + noise(rng))};
    f.z_min_m = noise(rng);
    f.z_max_m = 2.0 + noise(rng);
    const ObservationId obs = first_obs + rng() % 20;
    const RobotId robot = static_cast<RobotId>(rng() % 4);
    if (k == 0) {
      stats = ClusterStats::OfFeature(f, obs, robot);
    } else {
      stats.AddFeature(f, obs, robot, /*support_cap=*/8);
    }
  }
  return stats;
}

TEST(ClusterStatsTest, MergeAllEqualsMergingOneByOne) {
  std::mt19937 rng(5);
  for (int trial = 0; trial < 200; ++trial) {
    std::vector<ClusterStats> parts;
    const int count = 1 + trial % 6;
    for (int i = 0; i < count; ++i) {
      parts.push_back(RandomCluster(rng, 1000 * (i + 1), 30 * i));
    }
    ClusterStats one_by_one = parts[0];
    for (int i = 1; i < count; ++i) {
      ClusterStats copy = parts[i];
      one_by_one.Merge(std::move(copy), 8);
    }
    std::vector<const ClusterStats*> pointers;
    for (const ClusterStats& part : parts) pointers.push_back(&part);
    const std::vector<ClusterStats> before = parts;
    const ClusterStats all = ClusterStats::MergeAll(pointers, 8);
    for (int i = 0; i < count; ++i) {  // merged in place, not moved from
      ASSERT_EQ(parts[i].observations.ids(), before[i].observations.ids());
      ASSERT_EQ(parts[i].robots, before[i].robots);
      ASSERT_EQ(parts[i].hull, before[i].hull);
    }
    ASSERT_EQ(all.id, one_by_one.id);
    ASSERT_EQ(all.plane_members, one_by_one.plane_members);
    ASSERT_EQ(all.member_count, one_by_one.member_count);
    ASSERT_EQ(all.moments.count, one_by_one.moments.count);
    ASSERT_EQ(all.moments.mean, one_by_one.moments.mean);
    ASSERT_EQ(all.moments.scatter, one_by_one.moments.scatter);
    ASSERT_EQ(all.hull, one_by_one.hull) << "trial " << trial;
    ASSERT_EQ(all.support(), one_by_one.support());
    ASSERT_EQ(all.observations.ids(), one_by_one.observations.ids());
    ASSERT_EQ(all.robots, one_by_one.robots);
    ASSERT_EQ(all.z_min_m, one_by_one.z_min_m);
    ASSERT_EQ(all.z_max_m, one_by_one.z_max_m);
    const ClusterStats::Fit a = all.Refit(), b = one_by_one.Refit();
    ASSERT_EQ(a.segment.a, b.segment.a);
    ASSERT_EQ(a.segment.b, b.segment.b);
  }
}

}  // namespace
}  // namespace mapd::fusion
