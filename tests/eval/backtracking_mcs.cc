#include "eval/backtracking_mcs.h"

#include <algorithm>
#include <chrono>
#include <map>
#include <utility>

#include "voxel/rigid_fit.h"

namespace mapd::voxel {
namespace {

using Clock = std::chrono::steady_clock;
using Bits = std::vector<uint64_t>;

inline bool Test(const Bits& b, int v) { return (b[v >> 6] >> (v & 63)) & 1u; }

class Backtracker {
 public:
  Backtracker(const BitGraph& graph, const std::vector<CornerPair>& pairs,
              const std::vector<Eigen::Vector3d>& points_a,
              const std::vector<Eigen::Vector3d>& points_b, const BacktrackingOptions& options)
      : g_(graph),
        pairs_(pairs),
        pa_(points_a),
        pb_(points_b),
        options_(options),
        start_(Clock::now()) {
    std::map<int, std::vector<int>> by_a;
    for (int v = 0; v < g_.num_vertices(); ++v) by_a[pairs_[v].a].push_back(v);
    for (auto& [a, vs] : by_a) rows_.push_back(std::move(vs));
    P_.assign(g_.num_vertices() + 2, Bits(g_.num_words(), 0));
    for (int v = 0; v < g_.num_vertices(); ++v) P_[0][v >> 6] |= uint64_t{1} << (v & 63);
  }

  void Run() { Search(0, 0); }
  bool aborted() const { return aborted_; }
  int64_t nodes() const { return nodes_; }
  std::vector<std::vector<int>>& schemes() { return schemes_; }

 private:
  // Collecting ties until the list is full; then only a larger scheme matters.
  bool tie_mode() const {
    return options_.max_tied_solutions > 1 &&
           static_cast<int>(schemes_.size()) < options_.max_tied_solutions;
  }
  bool Prunes(int reachable) const { return tie_mode() ? reachable < best_ : reachable <= best_; }

  bool OutOfBudget() {
    if (options_.max_nodes > 0 && nodes_ >= options_.max_nodes) return true;
    if (options_.max_seconds > 0.0 && (nodes_ & 255) == 0) {
      return std::chrono::duration<double>(Clock::now() - start_).count() > options_.max_seconds;
    }
    return false;
  }

  void Record(std::vector<int> scheme) {
    const int size = static_cast<int>(scheme.size());
    if (size < best_ || size == 0) return;
    std::sort(scheme.begin(), scheme.end());
    if (size > best_) {
      best_ = size;
      schemes_.assign(1, std::move(scheme));
    } else if (tie_mode() &&
               std::find(schemes_.begin(), schemes_.end(), scheme) == schemes_.end()) {
      schemes_.push_back(std::move(scheme));
    }
  }

  // The shortcut: fit T_a_b to the current matches, then add every pair that
  // is consistent with them and lands within D, closest first.
  bool CompleteByTransform(int depth) {
    std::vector<Eigen::Vector3d> a, b;
    for (int v : matches_) {
      a.push_back(pa_[pairs_[v].a]);
      b.push_back(pb_[pairs_[v].b]);
    }
    const StatusOr<RigidFit> fit = FitRigidTransform(a, b);
    if (!fit.ok()) return false;  // degenerate: keep searching row by row
    const Eigen::Isometry3d& T_a_b = fit->T_target_source;
    std::vector<std::pair<double, int>> close;
    const Bits& P = P_[depth];
    for (int v = 0; v < g_.num_vertices(); ++v) {
      if (!Test(P, v)) continue;
      const double r = (pa_[pairs_[v].a] - T_a_b * pb_[pairs_[v].b]).norm();
      if (r < options_.consistency_distance_m) close.emplace_back(r, v);
    }
    std::sort(close.begin(), close.end());
    Bits Q = P;
    std::vector<int> scheme = matches_;
    for (const auto& [r, v] : close) {
      if (!Test(Q, v)) continue;
      scheme.push_back(v);
      const uint64_t* row = g_.Row(v);
      for (int w = 0; w < g_.num_words(); ++w) Q[w] &= row[w];
    }
    Record(std::move(scheme));
    return true;
  }

  // depth = matches_.size(); P_[depth] = candidates consistent with all matches.
  void Search(int row, int depth) {
    ++nodes_;
    if (OutOfBudget()) {
      aborted_ = true;
      return;
    }
    const int rows = static_cast<int>(rows_.size());
    if (Prunes(depth + rows - row)) return;
    if (row == rows) {
      Record(matches_);
      return;
    }
    for (int v : rows_[row]) {
      if (!Test(P_[depth], v)) continue;
      matches_.push_back(v);
      const uint64_t* nb = g_.Row(v);
      for (int w = 0; w < g_.num_words(); ++w) P_[depth + 1][w] = P_[depth][w] & nb[w];
      const bool closed = options_.shortcut_matches > 0 && depth + 1 == options_.shortcut_matches &&
                          CompleteByTransform(depth + 1);
      if (!closed) Search(row + 1, depth + 1);
      matches_.pop_back();
      if (aborted_) return;
    }
    Search(row + 1, depth);  // leave this corner of A unmatched
  }

  const BitGraph& g_;
  const std::vector<CornerPair>& pairs_;
  const std::vector<Eigen::Vector3d>& pa_;
  const std::vector<Eigen::Vector3d>& pb_;
  const BacktrackingOptions& options_;
  const Clock::time_point start_;
  std::vector<std::vector<int>> rows_;  // candidate vertices per corner of A
  std::vector<Bits> P_;                 // per depth
  std::vector<int> matches_;
  std::vector<std::vector<int>> schemes_;
  int best_ = 0;
  int64_t nodes_ = 0;
  bool aborted_ = false;
};

}  // namespace

BacktrackingResult FindCommonSubgraphByBacktracking(const BitGraph& graph,
                                                    const std::vector<CornerPair>& pairs,
                                                    const std::vector<Eigen::Vector3d>& points_a,
                                                    const std::vector<Eigen::Vector3d>& points_b,
                                                    const BacktrackingOptions& options) {
  const Clock::time_point start = Clock::now();
  Backtracker search(graph, pairs, points_a, points_b, options);
  search.Run();
  BacktrackingResult result;
  result.schemes = std::move(search.schemes());
  result.exhausted_search_space = !search.aborted();
  result.nodes = search.nodes();
  result.seconds = std::chrono::duration<double>(Clock::now() - start).count();
  return result;
}

PairSetSearch BacktrackingSearch(int shortcut_matches) {
  return [shortcut_matches](const BitGraph& graph, const std::vector<CornerPair>& pairs,
                            const std::vector<Eigen::Vector3d>& points_a,
                            const std::vector<Eigen::Vector3d>& points_b,
                            const CornerMatchingParams& params, int max_solutions) {
    BacktrackingOptions options;
    options.consistency_distance_m = params.consistency_distance_m;
    options.shortcut_matches = shortcut_matches;
    options.max_tied_solutions = max_solutions;
    options.max_nodes = params.max_search_nodes;
    options.max_seconds = params.max_search_seconds;
    BacktrackingResult r =
        FindCommonSubgraphByBacktracking(graph, pairs, points_a, points_b, options);
    PairSetSearchResult out;
    out.solutions = std::move(r.schemes);
    out.proven_optimal = r.exhausted_search_space && shortcut_matches == 0;
    out.nodes = r.nodes;
    out.seconds = r.seconds;
    return out;
  };
}

std::vector<NamedSearch> SearchesToCompare() {
  return {{"max_clique", nullptr}, {"backtracking", BacktrackingSearch()}};
}

}  // namespace mapd::voxel
