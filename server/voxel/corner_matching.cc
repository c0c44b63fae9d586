// Steps 2-4 of corner matching: graph, search, transform (see the header).
#include "voxel/corner_matching.h"

#include <algorithm>
#include <chrono>
#include <string>
#include <utility>

#include "common/clock.h"
#include "voxel/corner_directions.h"
#include "voxel/rigid_fit.h"

namespace mapd::voxel {
namespace {

using Clock = std::chrono::steady_clock;

// The default step 3: the exact maximum clique.
PairSetSearchResult MaxCliqueSearch(const BitGraph& graph, const CornerMatchingParams& params,
                                    int max_solutions) {
  MaxCliqueOptions options;
  options.max_nodes = params.max_search_nodes;
  options.max_seconds = params.max_search_seconds;
  options.max_tied_cliques = max_solutions;
  MaxCliqueResult r = FindMaximumClique(graph, options);
  PairSetSearchResult out;
  out.solutions = std::move(r.ties);
  out.proven_optimal = r.proven_optimal;
  out.nodes = r.nodes;
  out.seconds = r.seconds;
  return out;
}

Status CheckPoints(const std::vector<Eigen::Vector3d>& points, const char* name) {
  for (size_t i = 0; i < points.size(); ++i) {
    if (!points[i].allFinite()) {
      return Status::InvalidArgument(std::string(name) + "[" + std::to_string(i) +
                                     "] is not finite");
    }
  }
  return Status::Ok();
}

// Steps 3-4 on the consistency graph of `pairs` (vertex v = pairs[v]).
StatusOr<CornerMatchResult> Solve(const std::vector<Eigen::Vector3d>& points_a,
                                  const std::vector<Eigen::Vector3d>& points_b,
                                  const std::vector<CornerPair>& pairs, const BitGraph& graph,
                                  const CornerMatchingParams& params, const TransformScore& score,
                                  Clock::time_point start) {
  CornerMatchResult result;
  result.candidate_pairs = graph.num_vertices();
  result.graph_edges = graph.num_edges();
  result.graph_density = graph.density();

  const int max_solutions = score != nullptr ? params.max_tied_solutions : 1;
  const PairSetSearchResult found =
      params.search ? params.search(graph, pairs, points_a, points_b, params, max_solutions)
                    : MaxCliqueSearch(graph, params, max_solutions);
  result.search_nodes = found.nodes;
  result.search_seconds = found.seconds;
  result.proven_optimal = found.proven_optimal;
  result.tied_solutions = static_cast<int>(found.solutions.size());

  // Among equal-size solutions: the caller's best score, else the first.
  const std::vector<int>* chosen = nullptr;
  for (const std::vector<int>& solution : found.solutions) {
    std::vector<Eigen::Vector3d> a, b;
    for (int v : solution) {
      a.push_back(points_a[pairs[v].a]);
      b.push_back(points_b[pairs[v].b]);
    }
    const StatusOr<RigidFit> fit = FitRigidTransform(a, b);
    if (chosen == nullptr) chosen = &solution;  // kept even without a valid fit
    if (!fit.ok()) continue;
    const double s = score ? score(fit->T_target_source) : 0.0;
    if (!result.transform_valid || s > result.tie_score) {
      chosen = &solution;
      result.transform_valid = true;
      result.tie_score = s;
      result.T_a_b = fit->T_target_source;
      result.rms_residual_m = fit->rms_residual_m;
    }
    if (!score) break;
  }
  if (chosen != nullptr) {
    for (int v : *chosen) result.correspondences.push_back(pairs[v]);
    std::sort(result.correspondences.begin(), result.correspondences.end());
  }
  result.matched_count = static_cast<int>(result.correspondences.size());
  if (result.matched_count < params.min_matches) {
    result.transform_valid = false;
    result.T_a_b = Eigen::Isometry3d::Identity();
    result.rms_residual_m = 0.0;
  }
  result.total_seconds = SecondsSince(start);
  return result;
}

}  // namespace

Status CornerMatchingParams::Validate() const {
  auto bad = [](const std::string& what) {
    return Status::InvalidArgument("corner matching params: " + what);
  };
  if (!(consistency_distance_m > 0.0) || !std::isfinite(consistency_distance_m))
    return bad("consistency_distance_m must be positive and finite");
  if (top_k < 1) return bad("top_k must be >= 1");
  if (max_candidate_pairs < 0) return bad("max_candidate_pairs must be >= 0");
  if (!(signature_tolerance_rad >= 0.0)) return bad("signature_tolerance_rad must be >= 0");
  if (!(normal_tolerance_rad >= 0.0)) return bad("normal_tolerance_rad must be >= 0");
  if (min_matches < 3) return bad("min_matches must be >= 3 (a rigid transform needs 3)");
  if (max_tied_solutions < 1) return bad("max_tied_solutions must be >= 1");
  if (max_search_nodes < 0) return bad("max_search_nodes must be >= 0");
  if (!(max_search_seconds >= 0.0)) return bad("max_search_seconds must be >= 0");
  return Status::Ok();
}

BitGraph BuildConsistencyGraph(const std::vector<Eigen::Vector3d>& points_a,
                               const std::vector<Eigen::Vector3d>& points_b,
                               const std::vector<CornerPair>& pairs, double consistency_distance_m,
                               const PairConsistency& extra) {
  const int n = static_cast<int>(pairs.size());
  BitGraph graph(n);
  for (int i = 0; i < n; ++i) {
    const CornerPair& p = pairs[i];
    for (int j = i + 1; j < n; ++j) {
      const CornerPair& q = pairs[j];
      if (p.a == q.a || p.b == q.b) continue;
      const double da = (points_a[p.a] - points_a[q.a]).norm();
      const double db = (points_b[p.b] - points_b[q.b]).norm();
      if (std::abs(da - db) >= consistency_distance_m) continue;  // eq. (4)
      if (extra && !extra(p, q)) continue;
      graph.AddEdge(i, j);
    }
  }
  return graph;
}

StatusOr<CornerMatchResult> MatchCandidatePairs(const std::vector<Eigen::Vector3d>& points_a,
                                                const std::vector<Eigen::Vector3d>& points_b,
                                                const std::vector<CornerPair>& pairs,
                                                const CornerMatchingParams& params,
                                                const TransformScore& tie_score) {
  const Clock::time_point start = Clock::now();
  MAPD_RETURN_IF_ERROR(params.Validate());
  MAPD_RETURN_IF_ERROR(CheckPoints(points_a, "points_a"));
  MAPD_RETURN_IF_ERROR(CheckPoints(points_b, "points_b"));
  const int na = static_cast<int>(points_a.size());
  const int nb = static_cast<int>(points_b.size());
  for (size_t i = 0; i < pairs.size(); ++i) {
    if (pairs[i].a < 0 || pairs[i].a >= na || pairs[i].b < 0 || pairs[i].b >= nb) {
      return Status::InvalidArgument("pairs[" + std::to_string(i) + "] indexes out of range");
    }
  }
  const BitGraph graph =
      BuildConsistencyGraph(points_a, points_b, pairs, params.consistency_distance_m);
  return Solve(points_a, points_b, pairs, graph, params, tie_score, start);
}

StatusOr<CornerMatcher> CornerMatcher::Create(const CornerSet& corners_a,
                                              const CornerSet& corners_b,
                                              const CornerMatchingParams& params) {
  MAPD_RETURN_IF_ERROR(params.Validate());
  CornerMatcher m;
  m.params_ = params;
  m.params_.excluded_pairs.clear();
  for (const Corner& c : corners_a) m.points_a_.push_back(c.position);
  for (const Corner& c : corners_b) m.points_b_.push_back(c.position);
  MAPD_RETURN_IF_ERROR(CheckPoints(m.points_a_, "corners_a.position"));
  MAPD_RETURN_IF_ERROR(CheckPoints(m.points_b_, "corners_b.position"));
  for (const CornerSet* set : {&corners_a, &corners_b}) {
    for (size_t i = 0; i < set->size(); ++i) {
      for (const Eigen::Vector3d& n : (*set)[i].normals) {
        if (!n.allFinite() || n.norm() < 1e-9) {
          return Status::InvalidArgument(
              std::string(set == &corners_a ? "corners_a" : "corners_b") + "[" + std::to_string(i) +
              "] has a zero or non-finite normal");
        }
      }
    }
  }
  m.pairs_ = SelectCandidatePairs(corners_a, corners_b, params);

  PairConsistency normals_agree = nullptr;
  if (params.use_normals) {
    const auto& points_a = m.points_a_;
    const auto& points_b = m.points_b_;
    normals_agree = [&](const CornerPair& p, const CornerPair& q) {
      using internal::DirectionFeature;
      using internal::DirectionsAgree;
      const Eigen::Vector3d da = points_a[q.a] - points_a[p.a];
      const Eigen::Vector3d db = points_b[q.b] - points_b[p.b];
      const double la = da.norm();
      const double lb = db.norm();
      const double tol = internal::DirectionTolerance(
          params.normal_tolerance_rad, params.consistency_distance_m, std::min(la, lb));
      if (tol >= 1.0) return true;  // too close to tell directions apart
      return DirectionsAgree(DirectionFeature(corners_a[p.a], da / la),
                             DirectionFeature(corners_b[p.b], db / lb), tol) &&
             DirectionsAgree(DirectionFeature(corners_a[q.a], -da / la),
                             DirectionFeature(corners_b[q.b], -db / lb), tol);
    };
  }
  m.graph_ = BuildConsistencyGraph(m.points_a_, m.points_b_, m.pairs_,
                                   params.consistency_distance_m, normals_agree);
  return m;
}

StatusOr<CornerMatchResult> CornerMatcher::Match(
    const std::vector<std::pair<int, int>>& excluded_pairs, double max_search_seconds,
    const TransformScore& tie_score) const {
  const Clock::time_point start = Clock::now();
  CornerMatchingParams params = params_;
  params.max_search_seconds = max_search_seconds;
  MAPD_RETURN_IF_ERROR(params.Validate());
  if (excluded_pairs.empty()) {
    return Solve(points_a_, points_b_, pairs_, graph_, params, tie_score, start);
  }
  // The subgraph induced by the pairs not excluded, in their order: the
  // graph BuildConsistencyGraph gives for those pairs (an edge depends only
  // on its two pairs).
  std::vector<std::pair<int, int>> excluded = excluded_pairs;
  std::sort(excluded.begin(), excluded.end());
  std::vector<int> new_index(pairs_.size(), -1);
  std::vector<CornerPair> kept;
  for (std::size_t v = 0; v < pairs_.size(); ++v) {
    const CornerPair& p = pairs_[v];
    if (std::binary_search(excluded.begin(), excluded.end(), std::make_pair(p.a, p.b))) continue;
    new_index[v] = static_cast<int>(kept.size());
    kept.push_back(p);
  }
  BitGraph graph(static_cast<int>(kept.size()));
  for (std::size_t u = 0; u < pairs_.size(); ++u) {
    if (new_index[u] < 0) continue;
    const uint64_t* row = graph_.Row(static_cast<int>(u));
    for (int w = static_cast<int>(u >> 6); w < graph_.num_words(); ++w) {
      for (uint64_t bits = row[w]; bits != 0; bits &= bits - 1) {
        const int v = (w << 6) + __builtin_ctzll(bits);
        if (v > static_cast<int>(u) && new_index[static_cast<std::size_t>(v)] >= 0) {
          graph.AddEdge(new_index[u], new_index[static_cast<std::size_t>(v)]);
        }
      }
    }
  }
  return Solve(points_a_, points_b_, kept, graph, params, tie_score, start);
}

StatusOr<CornerMatchResult> MatchCorners(const CornerSet& corners_a, const CornerSet& corners_b,
                                         const CornerMatchingParams& params,
                                         const TransformScore& tie_score) {
  const Clock::time_point start = Clock::now();
  auto matcher = CornerMatcher::Create(corners_a, corners_b, params);
  if (!matcher.ok()) return matcher.status();
  auto result = matcher->Match(params.excluded_pairs, params.max_search_seconds, tie_score);
  if (result.ok()) result->total_seconds = SecondsSince(start);
  return result;
}

}  // namespace mapd::voxel
