#include "voxel/max_clique.h"

#include <algorithm>
#include <chrono>
#include <utility>

namespace mapd::voxel {
namespace {

using Clock = std::chrono::steady_clock;

inline int PopCount(uint64_t w) { return __builtin_popcountll(w); }
inline int LowestBit(uint64_t w) { return __builtin_ctzll(w); }

// Smallest-last (degeneracy) order: repeatedly remove a vertex of minimum
// remaining degree and put it at the back. Returns order[new_id] = old_id, so
// the densest core gets the lowest ids and is coloured first (MCS, BBMC).
std::vector<int> DegeneracyOrder(const BitGraph& g) {
  const int n = g.num_vertices();
  std::vector<int> degree(n);
  for (int v = 0; v < n; ++v) degree[v] = g.Degree(v);
  std::vector<bool> removed(n, false);
  std::vector<int> order(n);
  // O(n^2) selection; n is a few thousand at most here and this is dwarfed by
  // building the graph.
  for (int pos = n - 1; pos >= 0; --pos) {
    int best = -1;
    for (int v = 0; v < n; ++v) {
      if (removed[v]) continue;
      if (best < 0 || degree[v] < degree[best]) best = v;
    }
    removed[best] = true;
    order[pos] = best;
    const uint64_t* row = g.Row(best);
    for (int w = 0; w < g.num_words(); ++w) {
      uint64_t bits = row[w];
      while (bits) {
        const int u = w * 64 + LowestBit(bits);
        bits &= bits - 1;
        if (!removed[u]) --degree[u];
      }
    }
  }
  return order;
}

class Searcher {
 public:
  Searcher(const BitGraph& graph, const MaxCliqueOptions& options)
      : g_(graph),
        options_(options),
        words_(graph.num_words()),
        start_(Clock::now()),
        scratch_(graph.num_vertices() + 2) {}  // depth <= clique size + 1: never reallocates

  void Run() {
    std::vector<uint64_t> all(words_, 0);
    for (int v = 0; v < g_.num_vertices(); ++v) all[v >> 6] |= uint64_t{1} << (v & 63);
    Expand(all, 0);
  }

  bool aborted() const { return aborted_; }
  int64_t nodes() const { return nodes_; }
  std::vector<std::vector<int>>& ties() { return ties_; }

 private:
  // Collecting ties until the list is full; then only a larger clique matters.
  bool tie_mode() const {
    return options_.max_tied_cliques > 1 &&
           static_cast<int>(ties_.size()) < options_.max_tied_cliques;
  }

  bool OutOfBudget() {
    if (options_.max_nodes > 0 && nodes_ >= options_.max_nodes) return true;
    if (options_.max_seconds > 0.0 && (nodes_ & 255) == 0) {
      const double s = std::chrono::duration<double>(Clock::now() - start_).count();
      if (s > options_.max_seconds) return true;
    }
    return false;
  }

  // Can a clique of size `reachable` still matter?
  bool Prunes(int reachable) const { return tie_mode() ? reachable < best_ : reachable <= best_; }

  void Record() {
    const int size = static_cast<int>(current_.size());
    if (size > best_) {
      best_ = size;
      ties_.assign(1, current_);
    } else if (size == best_ && tie_mode()) {
      ties_.push_back(current_);
    }
  }

  // P: candidate set (modified: branched vertices are removed). depth indexes
  // the scratch buffers.
  void Expand(std::vector<uint64_t>& P, int depth) {
    ++nodes_;
    if (OutOfBudget()) {
      aborted_ = true;
      return;
    }
    Scratch& s = scratch_[depth];
    s.order.clear();
    s.colour.clear();
    s.U = P;
    s.Q.resize(words_);
    // Greedy sequential colouring in bit order (BBMC). Only vertices whose
    // colour can still lift |C| past the bound need to be branched on.
    const int csize = static_cast<int>(current_.size());
    int kmin = (tie_mode() ? best_ : best_ + 1) - csize;
    if (kmin < 1) kmin = 1;
    int k = 0;
    bool any = true;
    while (any) {
      any = false;
      ++k;
      s.Q = s.U;
      for (int w = 0; w < words_; ++w) {
        while (s.Q[w]) {
          const int v = w * 64 + LowestBit(s.Q[w]);
          s.Q[w] &= s.Q[w] - 1;
          s.U[w] &= ~(uint64_t{1} << (v & 63));
          const uint64_t* row = g_.Row(v);
          for (int x = w; x < words_; ++x) s.Q[x] &= ~row[x];
          if (k >= kmin) {
            s.order.push_back(v);
            s.colour.push_back(k);
          }
          any = true;
        }
      }
    }
    for (int i = static_cast<int>(s.order.size()) - 1; i >= 0; --i) {
      if (Prunes(csize + s.colour[i])) return;
      const int v = s.order[i];
      current_.push_back(v);
      std::vector<uint64_t>& child = scratch_[depth + 1].P;
      child.resize(words_);
      const uint64_t* row = g_.Row(v);
      bool empty = true;
      for (int w = 0; w < words_; ++w) {
        child[w] = P[w] & row[w];
        empty = empty && child[w] == 0;
      }
      if (empty) {
        Record();
      } else {
        Expand(child, depth + 1);
      }
      current_.pop_back();
      if (aborted_) return;
      P[v >> 6] &= ~(uint64_t{1} << (v & 63));
    }
  }

  struct Scratch {
    std::vector<uint64_t> P;  // the candidate set handed to the next depth
    std::vector<uint64_t> U, Q;
    std::vector<int> order, colour;
  };

  const BitGraph& g_;
  const MaxCliqueOptions& options_;
  const int words_;
  const Clock::time_point start_;
  std::vector<Scratch> scratch_;
  std::vector<int> current_;
  std::vector<std::vector<int>> ties_;
  int best_ = 0;
  int64_t nodes_ = 0;
  bool aborted_ = false;
};

}  // namespace

BitGraph::BitGraph(int num_vertices)
    : n_(num_vertices),
      words_((num_vertices + 63) / 64),
      bits_(static_cast<size_t>(n_) * words_, 0) {}

int64_t BitGraph::num_edges() const {
  int64_t sum = 0;
  for (uint64_t w : bits_) sum += PopCount(w);
  return sum / 2;
}

double BitGraph::density() const {
  if (n_ < 2) return 0.0;
  return static_cast<double>(num_edges()) / (0.5 * n_ * (n_ - 1.0));
}

void BitGraph::AddEdge(int u, int v) {
  bits_[static_cast<size_t>(u) * words_ + (v >> 6)] |= uint64_t{1} << (v & 63);
  bits_[static_cast<size_t>(v) * words_ + (u >> 6)] |= uint64_t{1} << (u & 63);
}

int BitGraph::Degree(int u) const {
  int d = 0;
  const uint64_t* row = Row(u);
  for (int w = 0; w < words_; ++w) d += PopCount(row[w]);
  return d;
}

bool IsClique(const BitGraph& graph, const std::vector<int>& vertices) {
  for (size_t i = 0; i < vertices.size(); ++i) {
    for (size_t j = i + 1; j < vertices.size(); ++j) {
      if (vertices[i] == vertices[j] || !graph.HasEdge(vertices[i], vertices[j])) return false;
    }
  }
  return true;
}

MaxCliqueResult FindMaximumClique(const BitGraph& graph, const MaxCliqueOptions& options) {
  const Clock::time_point start = Clock::now();
  MaxCliqueResult result;
  const int n = graph.num_vertices();
  if (n == 0) {
    result.proven_optimal = true;
    return result;
  }
  // Renumber so that bit order is the degeneracy order.
  const std::vector<int> order = DegeneracyOrder(graph);
  std::vector<int> new_id(n);
  for (int i = 0; i < n; ++i) new_id[order[i]] = i;
  BitGraph renumbered(n);
  for (int u = 0; u < n; ++u) {
    const uint64_t* row = graph.Row(u);
    for (int w = 0; w < graph.num_words(); ++w) {
      uint64_t bits = row[w];
      while (bits) {
        const int v = w * 64 + LowestBit(bits);
        bits &= bits - 1;
        if (u < v) renumbered.AddEdge(new_id[u], new_id[v]);
      }
    }
  }

  Searcher searcher(renumbered, options);
  searcher.Run();
  for (std::vector<int>& clique : searcher.ties()) {
    for (int& v : clique) v = order[v];
    std::sort(clique.begin(), clique.end());
  }
  result.ties = std::move(searcher.ties());
  if (!result.ties.empty()) result.clique = result.ties.front();
  result.proven_optimal = !searcher.aborted();
  result.nodes = searcher.nodes();
  result.seconds = std::chrono::duration<double>(Clock::now() - start).count();
  return result;
}

}  // namespace mapd::voxel
