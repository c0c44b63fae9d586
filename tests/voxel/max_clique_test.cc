// The maximum clique search against brute force on random graphs, ties,
// planted cliques, and its budget.
#include "voxel/max_clique.h"

#include <gtest/gtest.h>

#include <random>
#include <vector>

namespace mapd::voxel {
namespace {

BitGraph RandomGraph(int n, double density, uint32_t seed) {
  std::mt19937 rng(seed);
  std::bernoulli_distribution edge(density);
  BitGraph g(n);
  for (int u = 0; u < n; ++u) {
    for (int v = u + 1; v < n; ++v) {
      if (edge(rng)) g.AddEdge(u, v);
    }
  }
  return g;
}

// Size of the largest clique by trying every subset (n <= 20).
int BruteForceCliqueSize(const BitGraph& g) {
  const int n = g.num_vertices();
  int best = 0;
  for (uint32_t mask = 1; mask < (1u << n); ++mask) {
    const int size = __builtin_popcount(mask);
    if (size <= best) continue;
    std::vector<int> vs;
    for (int v = 0; v < n; ++v) {
      if (mask & (1u << v)) vs.push_back(v);
    }
    if (IsClique(g, vs)) best = size;
  }
  return best;
}

TEST(MaxCliqueTest, MatchesBruteForceOnSmallRandomGraphs) {
  uint32_t seed = 1;
  for (int n : {1, 2, 5, 9, 13, 17}) {
    for (double density : {0.1, 0.3, 0.5, 0.7, 0.9}) {
      for (int rep = 0; rep < 4; ++rep, ++seed) {
        const BitGraph g = RandomGraph(n, density, seed);
        const MaxCliqueResult r = FindMaximumClique(g);
        ASSERT_TRUE(r.proven_optimal);
        EXPECT_TRUE(IsClique(g, r.clique)) << "seed " << seed;
        EXPECT_EQ(static_cast<int>(r.clique.size()), BruteForceCliqueSize(g))
            << "n " << n << " density " << density << " seed " << seed;
      }
    }
  }
}

TEST(MaxCliqueTest, CollectsEveryTiedMaximumClique) {
  uint32_t seed = 100;
  for (int rep = 0; rep < 20; ++rep, ++seed) {
    const BitGraph g = RandomGraph(14, 0.5, seed);
    const int best = BruteForceCliqueSize(g);
    int count = 0;  // brute-force number of maximum cliques
    for (uint32_t mask = 1; mask < (1u << 14); ++mask) {
      if (__builtin_popcount(mask) != best) continue;
      std::vector<int> vs;
      for (int v = 0; v < 14; ++v) {
        if (mask & (1u << v)) vs.push_back(v);
      }
      if (IsClique(g, vs)) ++count;
    }
    MaxCliqueOptions options;
    options.max_tied_cliques = 1000;
    const MaxCliqueResult r = FindMaximumClique(g, options);
    EXPECT_EQ(static_cast<int>(r.ties.size()), count) << "seed " << seed;
    for (const auto& c : r.ties) {
      EXPECT_EQ(static_cast<int>(c.size()), best);
      EXPECT_TRUE(IsClique(g, c));
    }
  }
}

TEST(MaxCliqueTest, KnownGraphs) {
  EXPECT_TRUE(FindMaximumClique(BitGraph(0)).clique.empty());
  EXPECT_EQ(FindMaximumClique(BitGraph(5)).clique.size(), 1u);  // no edges

  BitGraph complete(70);  // spans two bitset words
  for (int u = 0; u < 70; ++u)
    for (int v = u + 1; v < 70; ++v) complete.AddEdge(u, v);
  EXPECT_EQ(FindMaximumClique(complete).clique.size(), 70u);
  EXPECT_DOUBLE_EQ(complete.density(), 1.0);

  BitGraph c5(5);
  for (int v = 0; v < 5; ++v) c5.AddEdge(v, (v + 1) % 5);
  EXPECT_EQ(FindMaximumClique(c5).clique.size(), 2u);

  // Petersen graph: triangle-free, omega = 2.
  BitGraph petersen(10);
  for (int v = 0; v < 5; ++v) {
    petersen.AddEdge(v, (v + 1) % 5);
    petersen.AddEdge(v, v + 5);
    petersen.AddEdge(5 + v, 5 + (v + 2) % 5);
  }
  EXPECT_EQ(petersen.num_edges(), 15);
  EXPECT_EQ(FindMaximumClique(petersen).clique.size(), 2u);

  // Complement of a perfect matching on 2k vertices (cocktail party): omega = k.
  BitGraph party(16);
  for (int u = 0; u < 16; ++u)
    for (int v = u + 1; v < 16; ++v)
      if (v != u + 8) party.AddEdge(u, v);
  MaxCliqueOptions options;
  options.max_tied_cliques = 1000;
  const MaxCliqueResult r = FindMaximumClique(party, options);
  EXPECT_EQ(r.clique.size(), 8u);
  EXPECT_EQ(r.ties.size(), 256u);  // one of each matched pair: 2^8
}

TEST(MaxCliqueTest, FindsPlantedCliqueInSparseGraph) {
  BitGraph g = RandomGraph(1000, 0.05, 7);
  std::vector<int> planted;
  for (int v = 0; v < 1000; v += 37) planted.push_back(v);  // 28 vertices
  for (size_t i = 0; i < planted.size(); ++i)
    for (size_t j = i + 1; j < planted.size(); ++j) g.AddEdge(planted[i], planted[j]);
  const MaxCliqueResult r = FindMaximumClique(g);
  EXPECT_TRUE(r.proven_optimal);
  EXPECT_EQ(r.clique, planted);
}

TEST(MaxCliqueTest, BudgetStopsTheSearchAndSaysSo) {
  const BitGraph g = RandomGraph(300, 0.9, 3);
  MaxCliqueOptions options;
  options.max_nodes = 200;
  const MaxCliqueResult r = FindMaximumClique(g, options);
  EXPECT_FALSE(r.proven_optimal);
  EXPECT_LE(r.nodes, 200);
  EXPECT_FALSE(r.clique.empty());
  EXPECT_TRUE(IsClique(g, r.clique));
}

}  // namespace
}  // namespace mapd::voxel
