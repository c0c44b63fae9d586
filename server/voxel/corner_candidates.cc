// Step 1 of corner matching: signatures and the top-k candidate pairs.
#include <algorithm>
#include <cmath>
#include <vector>

#include "voxel/corner_directions.h"
#include "voxel/corner_matching.h"

namespace mapd::voxel {
namespace {

using internal::DirectionFeature;
using internal::DirectionsAgree;
using internal::DirectionTolerance;

struct Neighbour {
  double distance_m;
  Eigen::Vector3d feature;  // DirectionFeature of the direction to it
};

// Every other corner of the set, by ascending distance.
std::vector<std::vector<Neighbour>> NeighbourLists(const CornerSet& corners) {
  const int n = static_cast<int>(corners.size());
  std::vector<std::vector<Neighbour>> lists(n);
  for (int i = 0; i < n; ++i) {
    lists[i].reserve(n - 1);
    for (int j = 0; j < n; ++j) {
      if (j == i) continue;
      const Eigen::Vector3d d = corners[j].position - corners[i].position;
      const double len = d.norm();
      const Eigen::Vector3d f =
          len > 0.0 ? DirectionFeature(corners[i], d / len) : Eigen::Vector3d::Zero();
      lists[i].push_back({len, f});
    }
    std::sort(lists[i].begin(), lists[i].end(),
              [](const Neighbour& x, const Neighbour& y) { return x.distance_m < y.distance_m; });
  }
  return lists;
}

// How many other corners of A have a partner in B consistent with the pair
// (a, b): the pair's degree in the all-to-all consistency graph, counted once
// per corner of A. A true pair scores about the size of the overlap; a wrong
// one only chance agreements.
int ContextScore(const std::vector<Neighbour>& na, const std::vector<Neighbour>& nb,
                 const CornerMatchingParams& params) {
  const double D = params.consistency_distance_m;
  int count = 0;
  size_t lo = 0;
  for (const Neighbour& x : na) {
    while (lo < nb.size() && nb[lo].distance_m <= x.distance_m - D) ++lo;
    for (size_t j = lo; j < nb.size() && nb[j].distance_m < x.distance_m + D; ++j) {
      const double tol = DirectionTolerance(params.normal_tolerance_rad, D,
                                            std::min(x.distance_m, nb[j].distance_m));
      if (!params.use_normals || DirectionsAgree(x.feature, nb[j].feature, tol)) {
        ++count;
        break;
      }
    }
  }
  return count;
}

double SignatureDifference(const CornerSignature& x, const CornerSignature& y) {
  double d = 0.0;
  for (int k = 0; k < 3; ++k)
    d = std::max(d, std::abs(x.plane_angles_rad[k] - y.plane_angles_rad[k]));
  return d;
}

struct Ranked {
  int score;
  double signature_difference;
  int other;
  bool operator<(const Ranked& o) const {  // better first
    if (score != o.score) return score > o.score;
    if (signature_difference != o.signature_difference)
      return signature_difference < o.signature_difference;
    return other < o.other;
  }
};

void KeepTopK(std::vector<Ranked>* ranked, int k) {
  if (static_cast<int>(ranked->size()) > k) {
    std::partial_sort(ranked->begin(), ranked->begin() + k, ranked->end());
    ranked->resize(k);
  }
}

}  // namespace

CornerSignature ComputeSignature(const Corner& corner) {
  Eigen::Vector3d n[3];
  for (int k = 0; k < 3; ++k) n[k] = corner.normals[k].normalized();
  CornerSignature s;
  const int pairs[3][2] = {{0, 1}, {0, 2}, {1, 2}};
  for (int p = 0; p < 3; ++p) {
    const double c = std::min(1.0, std::abs(n[pairs[p][0]].dot(n[pairs[p][1]])));
    s.plane_angles_rad[p] = std::acos(c);
  }
  std::sort(s.plane_angles_rad.begin(), s.plane_angles_rad.end());
  return s;
}

std::vector<CornerPair> SelectCandidatePairs(const CornerSet& corners_a, const CornerSet& corners_b,
                                             const CornerMatchingParams& params) {
  const int na = static_cast<int>(corners_a.size());
  const int nb = static_cast<int>(corners_b.size());
  std::vector<CornerSignature> sig_a(na), sig_b(nb);
  for (int i = 0; i < na; ++i) sig_a[i] = ComputeSignature(corners_a[i]);
  for (int j = 0; j < nb; ++j) sig_b[j] = ComputeSignature(corners_b[j]);
  const auto lists_a = NeighbourLists(corners_a);
  const auto lists_b = NeighbourLists(corners_b);

  // A pair in a clique of min_matches has at least min_matches - 1 consistent
  // partners; fewer cannot be part of an acceptable answer.
  const int min_score = std::max(0, params.min_matches - 1);
  std::vector<std::vector<Ranked>> for_a(na), for_b(nb);
  for (int i = 0; i < na; ++i) {
    for (int j = 0; j < nb; ++j) {
      const double sd = SignatureDifference(sig_a[i], sig_b[j]);
      if (sd > params.signature_tolerance_rad) continue;
      const int score = ContextScore(lists_a[i], lists_b[j], params);
      if (score < min_score) continue;
      for_a[i].push_back({score, sd, j});
      for_b[j].push_back({score, sd, i});
    }
  }
  // The largest k <= top_k whose pairs (counted before removing duplicates)
  // fit max_candidate_pairs; at least 1.
  int k = params.top_k;
  if (params.max_candidate_pairs > 0) {
    auto count = [&](int kk) {
      std::size_t n = 0;
      for (const auto& r : for_a)
        n += std::min<std::size_t>(r.size(), static_cast<std::size_t>(kk));
      for (const auto& r : for_b)
        n += std::min<std::size_t>(r.size(), static_cast<std::size_t>(kk));
      return n;
    };
    while (k > 1 && count(k) > static_cast<std::size_t>(params.max_candidate_pairs)) --k;
  }
  std::vector<CornerPair> pairs;
  for (int i = 0; i < na; ++i) {
    KeepTopK(&for_a[i], k);
    for (const Ranked& r : for_a[i]) pairs.push_back({i, r.other});
  }
  for (int j = 0; j < nb; ++j) {
    KeepTopK(&for_b[j], k);
    for (const Ranked& r : for_b[j]) pairs.push_back({r.other, j});
  }
  std::sort(pairs.begin(), pairs.end());
  pairs.erase(std::unique(pairs.begin(), pairs.end()), pairs.end());
  return pairs;
}

}  // namespace mapd::voxel
