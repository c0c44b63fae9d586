// The paper's maximum common subgraph search (grid-map-fusion paper, Qiu et
// al., section IV.C, Algorithm 1, after McGregor 1982; docs/algorithms.md
// B.4), on the consistency graph of corner_matching.h.
//
// Rows are the corners of A that have candidate pairs. Row by row the search
// either matches the corner to one of its candidate partners that is
// consistent with every match so far, or leaves it unmatched, and backtracks
// over all choices. A branch is cut when even matching every remaining row
// cannot beat the best scheme. The paper's shortcut: once `shortcut_matches`
// matches are chosen, fit a transform to them, add every candidate pair that
// lands within D of it (and is consistent), and take that as the scheme of the
// branch. With the shortcut the search is a heuristic; without it, exact.
//
// Test and benchmark support (mapd searches by maximum clique): plugged into
// corner matching through CornerMatchingParams::search.
#ifndef MAPD_EVAL_BACKTRACKING_MCS_H_
#define MAPD_EVAL_BACKTRACKING_MCS_H_

#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

#include "voxel/corner_matching.h"
#include "voxel/max_clique.h"

namespace mapd::voxel {

struct BacktrackingOptions {
  double consistency_distance_m = 0.2;  // D
  int shortcut_matches = 5;             // 0: no shortcut
  int max_tied_solutions = 1;           // > 1: collect distinct schemes of the best size
  int64_t max_nodes = 0;                // 0 = unlimited
  double max_seconds = 0.0;             // 0 = unlimited
};

struct BacktrackingResult {
  std::vector<std::vector<int>>
      schemes;  // vertex ids (ascending) of the best size, first found first
  bool exhausted_search_space = false;  // finished within the budget
  int64_t nodes = 0;
  double seconds = 0.0;
};

// Vertex v of `graph` is pairs[v] (see BuildConsistencyGraph).
BacktrackingResult FindCommonSubgraphByBacktracking(const BitGraph& graph,
                                                    const std::vector<CornerPair>& pairs,
                                                    const std::vector<Eigen::Vector3d>& points_a,
                                                    const std::vector<Eigen::Vector3d>& points_b,
                                                    const BacktrackingOptions& options);

// The search above as step 3 of corner matching: consistency_distance_m, the
// tie count and the budget come from the matching params.
// REQUIRES: shortcut_matches == 0 (exhaustive) or >= 3.
PairSetSearch BacktrackingSearch(int shortcut_matches = 5);

// The searches the tests and benchmarks compare, by name: "max_clique" (null,
// mapd's default) and "backtracking" (the paper's, with its shortcut).
struct NamedSearch {
  std::string name;
  PairSetSearch search;
};
std::vector<NamedSearch> SearchesToCompare();

}  // namespace mapd::voxel

#endif  // MAPD_EVAL_BACKTRACKING_MCS_H_
