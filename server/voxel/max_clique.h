// Exact maximum clique by branch and bound on adjacency bitsets
// (docs/algorithms.md B.4). The search is Tomita's MCQ/MCS scheme in the bitset
// form of San Segundo's BBMC: vertices renumbered in a degeneracy (smallest
// last) order, a greedy colouring of the candidate set at every node gives
// the bound |C| + colours(P) <= best => prune, and the vertices of the highest
// colour classes are branched on first.
//
// Exponential in the worst case: a budget of nodes and wall time stops the
// search, and the result says whether it is proven optimal.
#ifndef MAPD_VOXEL_MAX_CLIQUE_H_
#define MAPD_VOXEL_MAX_CLIQUE_H_

#include <cstddef>
#include <cstdint>
#include <vector>

namespace mapd::voxel {

// An undirected simple graph as one bitset row per vertex (uint64 words).
// Not thread safe for writes; const access is.
class BitGraph {
 public:
  BitGraph() = default;
  explicit BitGraph(int num_vertices);

  int num_vertices() const { return n_; }
  int num_words() const { return words_; }
  int64_t num_edges() const;
  // Edges / (n (n - 1) / 2); 0 for n < 2.
  double density() const;

  // REQUIRES: 0 <= u, v < num_vertices(), u != v.
  void AddEdge(int u, int v);
  bool HasEdge(int u, int v) const { return (Row(u)[v >> 6] >> (v & 63)) & 1u; }
  int Degree(int u) const;
  // The neighbourhood of u: num_words() words, bit v set when {u, v} is an edge.
  const uint64_t* Row(int u) const { return bits_.data() + static_cast<size_t>(u) * words_; }

 private:
  int n_ = 0;
  int words_ = 0;
  std::vector<uint64_t> bits_;
};

struct MaxCliqueOptions {
  int64_t max_nodes = 0;     // search-tree nodes; 0 = unlimited
  double max_seconds = 0.0;  // wall time; 0 = unlimited
  // > 1: also collect up to this many distinct cliques of the maximum size
  // (for tie-breaking by the caller). Costs more search: ties cannot be
  // pruned with "<=" but only with "<".
  int max_tied_cliques = 1;
};

struct MaxCliqueResult {
  std::vector<int> clique;             // vertex ids, ascending; the first maximum found
  std::vector<std::vector<int>> ties;  // all collected cliques of clique.size(), incl. clique
  bool proven_optimal = false;         // the search finished within its budget
  int64_t nodes = 0;                   // search-tree nodes expanded
  double seconds = 0.0;
};

// The maximum clique of `graph` (empty for an empty graph).
MaxCliqueResult FindMaximumClique(const BitGraph& graph, const MaxCliqueOptions& options = {});

// True if every two of `vertices` are adjacent (and they are distinct).
bool IsClique(const BitGraph& graph, const std::vector<int>& vertices);

}  // namespace mapd::voxel

#endif  // MAPD_VOXEL_MAX_CLIQUE_H_
