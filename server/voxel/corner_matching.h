// Corner matching between two voxel submaps (docs/algorithms.md B.4, B.5;
// grid-map-fusion paper, Qiu et al., section IV).
//
// Correspondences M = {(a_i, b_i)} must satisfy the paper's eq. (4):
//   | |a_i - a_j| - |b_i - b_j| | < D  for every two of them,
// i.e. M is a clique of the consistency graph whose vertices are candidate
// pairs (a, b). Pipeline:
//   1. Candidate pairs: every corner keeps its top_k most similar partners in
//      the other map (union over both sides). Similarity = rotation-invariant
//      local signatures: the sorted angles between the corner's three planes
//      (a gate), then the number of other corners that would be consistent
//      with the pair (its degree in the all-to-all graph, a "distance
//      context"), which also checks the directions to those corners against
//      the corner's own normals.
//   2. The consistency graph over candidate pairs (eq. (4), distinct corners,
//      optionally the same direction-vs-normals check).
//   3. Its maximum clique: exact branch and bound (max_clique.h). Tests and
//      benchmarks can plug in another search (CornerMatchingParams::search),
//      e.g. the paper's backtracking search (tests/eval/backtracking_mcs.h).
//   4. T_a_b by Umeyama without scaling on the matched corner positions.
// Ties on the clique size go to a caller's score of the transform (the paper:
// the most coinciding occupied voxels).
//
// Pure Eigen; thread compatible (no shared state).
#ifndef MAPD_VOXEL_CORNER_MATCHING_H_
#define MAPD_VOXEL_CORNER_MATCHING_H_

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <cmath>
#include <cstdint>
#include <functional>
#include <utility>
#include <vector>

#include "common/status.h"
#include "voxel/corner.h"
#include "voxel/max_clique.h"

namespace mapd::voxel {

struct CornerMatchingParams;
struct CornerPair;

// What step 3 found: sets of mutually consistent candidate pairs (graph
// vertex ids, ascending) of the best size, first found first.
struct PairSetSearchResult {
  std::vector<std::vector<int>> solutions;
  bool proven_optimal = false;  // no larger set exists in the graph
  int64_t nodes = 0;
  double seconds = 0.0;
};

// Step 3 as a function: vertex v of `graph` is pairs[v]; at most max_solutions
// equal-size sets; the budget is params.max_search_nodes / max_search_seconds.
using PairSetSearch = std::function<PairSetSearchResult(
    const BitGraph& graph, const std::vector<CornerPair>& pairs,
    const std::vector<Eigen::Vector3d>& points_a, const std::vector<Eigen::Vector3d>& points_b,
    const CornerMatchingParams& params, int max_solutions)>;

struct CornerMatchingParams {
  // Step 3; null: the exact maximum clique (max_clique.h), mapd's search
  // (faster than the paper's, see docs/voxel-matching.md).
  PairSetSearch search;
  // D of eq. (4), metres. Default: 2 voxels of 10 cm; use 2 * voxel size.
  double consistency_distance_m = 0.2;
  // Candidate partners kept per corner, for each corner of A and of B.
  int top_k = 8;
  // Cap on the candidate pairs (graph vertices); 0 = none. Above it top_k is
  // lowered for every corner until the pairs fit: the graph is built in
  // O(pairs^2) (fr_078_tidyup.bt, ~1000 corners x 32: 4.6 s of matching).
  int max_candidate_pairs = 0;
  // Candidates must agree on every sorted inter-plane angle within this.
  double signature_tolerance_rad = 10.0 * M_PI / 180.0;
  // Check the direction to other corners against the corner's normals (in
  // the signature score and in the graph's edges). Tolerated angular error of
  // a normal; the position part (2 D / distance) is added automatically.
  bool use_normals = true;
  double normal_tolerance_rad = 6.0 * M_PI / 180.0;
  // Fewer consistent matches than this: no transform (transform_valid false).
  int min_matches = 3;
  // With a tie-break score: at most this many equal-size solutions are scored.
  int max_tied_solutions = 16;
  // Search budget; exhausted => proven_optimal false, best found returned.
  int64_t max_search_nodes = 0;      // 0 = unlimited
  double max_search_seconds = 10.0;  // 0 = unlimited
  // Candidate pairs (index into A, index into B) never to use, e.g. those of a
  // solution that alignment refused, so the next search finds another one.
  std::vector<std::pair<int, int>> excluded_pairs;

  // InvalidArgument naming the first bad field.
  Status Validate() const;
};

// Rotation-invariant signature of one corner.
struct CornerSignature {
  // Angles between the three planes (normals as unoriented lines), radians in
  // [0, pi/2], ascending.
  std::array<double, 3> plane_angles_rad{};
};

CornerSignature ComputeSignature(const Corner& corner);

struct CornerPair {
  int a = 0;  // index into corners (points) of A
  int b = 0;  // index into corners (points) of B
  bool operator==(const CornerPair& o) const { return a == o.a && b == o.b; }
  bool operator<(const CornerPair& o) const { return a != o.a ? a < o.a : b < o.b; }
};

// Candidate pairs for the consistency graph (step 1), sorted, unique.
std::vector<CornerPair> SelectCandidatePairs(const CornerSet& corners_a, const CornerSet& corners_b,
                                             const CornerMatchingParams& params);

// An optional extra edge test on two candidate pairs (e.g. normals).
using PairConsistency = std::function<bool(const CornerPair&, const CornerPair&)>;

// Vertex v of the graph is pairs[v]. Edge when the pairs use distinct corners
// on both sides, satisfy eq. (4) with D = consistency_distance_m, and pass
// `extra` if given.
BitGraph BuildConsistencyGraph(const std::vector<Eigen::Vector3d>& points_a,
                               const std::vector<Eigen::Vector3d>& points_b,
                               const std::vector<CornerPair>& pairs, double consistency_distance_m,
                               const PairConsistency& extra = nullptr);

// Scores a candidate T_a_b; higher is better (e.g. coinciding occupied voxels).
using TransformScore = std::function<double(const Eigen::Isometry3d& T_a_b)>;

struct CornerMatchResult {
  std::vector<CornerPair> correspondences;                  // sorted by a
  Eigen::Isometry3d T_a_b = Eigen::Isometry3d::Identity();  // maps B's frame into A's
  bool transform_valid = false;                             // >= min_matches, not collinear
  double rms_residual_m = 0.0;                              // of T_a_b on the correspondences
  int matched_count = 0;                                    // correspondences.size()
  // Diagnostics.
  int candidate_pairs = 0;  // graph vertices
  int64_t graph_edges = 0;
  double graph_density = 0.0;
  int64_t search_nodes = 0;
  int tied_solutions = 1;       // equal-size solutions compared (>1 only with a score)
  double tie_score = 0.0;       // the score callback's value of the chosen T_a_b, if given
  bool proven_optimal = false;  // the clique is maximum in the graph (not for the shortcut)
  double search_seconds = 0.0;
  double total_seconds = 0.0;  // signatures + graph + search + fit
};

// The full pipeline on two corner sets. InvalidArgument for bad params or
// non-finite input. An OK result may have transform_valid == false: too
// little evidence is an answer, not an error.
StatusOr<CornerMatchResult> MatchCorners(const CornerSet& corners_a, const CornerSet& corners_b,
                                         const CornerMatchingParams& params,
                                         const TransformScore& tie_score = nullptr);

// The full pipeline run again and again with more candidate pairs excluded
// (merge_pair.cc: a refused solution's pairs are excluded and the search
// rerun). Steps 1-2 depend only on the corners and the params, so Create
// runs them once; Match searches the subgraph the pairs not excluded induce,
// which is the graph MatchCorners builds for them (same vertices in the same
// order: an edge depends only on its two pairs), so Match(excluded, ...)
// equals MatchCorners with params.excluded_pairs = excluded.
class CornerMatcher {
 public:
  // InvalidArgument for bad params or non-finite input (MatchCorners's);
  // params.excluded_pairs is ignored. Keeps copies: the sets may go.
  static StatusOr<CornerMatcher> Create(const CornerSet& corners_a, const CornerSet& corners_b,
                                        const CornerMatchingParams& params);
  // Steps 3-4 without `excluded_pairs` (index into A, index into B), the
  // search within max_search_seconds (0 = unlimited).
  StatusOr<CornerMatchResult> Match(const std::vector<std::pair<int, int>>& excluded_pairs,
                                    double max_search_seconds,
                                    const TransformScore& tie_score = nullptr) const;

 private:
  CornerMatcher() = default;
  CornerMatchingParams params_;
  std::vector<Eigen::Vector3d> points_a_, points_b_;
  std::vector<CornerPair> pairs_;  // step 1, sorted
  BitGraph graph_;                 // step 2 over pairs_
};

// Steps 2-4 on given candidate pairs between two point sets (no signatures,
// no normals; e.g. putative correspondences from descriptors).
StatusOr<CornerMatchResult> MatchCandidatePairs(const std::vector<Eigen::Vector3d>& points_a,
                                                const std::vector<Eigen::Vector3d>& points_b,
                                                const std::vector<CornerPair>& pairs,
                                                const CornerMatchingParams& params,
                                                const TransformScore& tie_score = nullptr);

}  // namespace mapd::voxel

#endif  // MAPD_VOXEL_CORNER_MATCHING_H_
