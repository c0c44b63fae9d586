#include "fusion/chain_guard.h"

#include <algorithm>
#include <cmath>
#include <utility>

namespace mapd::fusion {
namespace {

using geometry::PointMoments2;

void AddMember(const GuardMember& member, PointMoments2* m) {
  if (member.folded != nullptr) {
    m->Merge(*member.folded);
    return;
  }
  m->Add(member.segment.a);
  m->Add(member.segment.b);
}

PointMoments2 MomentsOf(const std::vector<GuardMember>& members,
                        const std::vector<uint32_t>& subset) {
  PointMoments2 m;
  for (uint32_t i : subset) AddMember(members[i], &m);
  return m;
}

bool ExceedsRms(double sse_m2, uint64_t point_count, double max_rms_m) {
  return sse_m2 > max_rms_m * max_rms_m * static_cast<double>(point_count);
}

}  // namespace

double OrthogonalSse(const PointMoments2& m) {
  const Eigen::Matrix2d& s = m.scatter;
  const double half_trace = 0.5 * (s(0, 0) + s(1, 1));
  const double radius = std::hypot(0.5 * (s(0, 0) - s(1, 1)), s(0, 1));
  return std::max(0.0, half_trace - radius);
}

bool ChainMayNeedSplit(const PointMoments2& endpoint_moments, double max_rms_m) {
  return max_rms_m > 0.0 && endpoint_moments.count > 2 &&
         ExceedsRms(OrthogonalSse(endpoint_moments), endpoint_moments.count, max_rms_m);
}

std::vector<std::vector<uint32_t>> SplitChain(const std::vector<GuardMember>& members,
                                              double max_rms_m, double max_sse_ratio,
                                              const CutAllowed& cut_allowed) {
  std::vector<uint32_t> all(members.size());
  for (uint32_t i = 0; i < all.size(); ++i) all[i] = i;
  std::vector<std::vector<uint32_t>> groups;
  // Depth-first with an explicit stack: a long arc can be cut many times.
  std::vector<std::vector<uint32_t>> stack;
  stack.push_back(std::move(all));
  while (!stack.empty()) {
    std::vector<uint32_t> subset = std::move(stack.back());
    stack.pop_back();
    const size_t n = subset.size();
    const PointMoments2 whole = MomentsOf(members, subset);
    const double sse_m2 = OrthogonalSse(whole);
    if (max_rms_m <= 0.0 || n < 2 || !ExceedsRms(sse_m2, whole.count, max_rms_m)) {
      std::sort(subset.begin(), subset.end());
      groups.push_back(std::move(subset));
      continue;
    }
    // Step 3: order along the fitted direction, ties by FeatureId.
    const geometry::Line2 line = geometry::FitLine(whole);
    std::vector<std::pair<double, uint32_t>> keyed;
    keyed.reserve(n);
    for (uint32_t i : subset) {
      keyed.emplace_back((members[i].segment.midpoint() - line.point).dot(line.direction), i);
    }
    std::sort(keyed.begin(), keyed.end(), [&](const auto& x, const auto& y) {
      if (x.first != y.first) return x.first < y.first;
      return members[x.second].id < members[y.second].id;
    });
    // prefix[k] = SSE(first k), suffix[k] = SSE(members k .. n-1).
    std::vector<double> prefix(n + 1, 0.0), suffix(n + 1, 0.0);
    PointMoments2 running;
    for (size_t k = 0; k < n; ++k) {
      AddMember(members[keyed[k].second], &running);
      prefix[k + 1] = OrthogonalSse(running);
    }
    running = PointMoments2();
    for (size_t k = n; k-- > 0;) {
      AddMember(members[keyed[k].second], &running);
      suffix[k] = OrthogonalSse(running);
    }
    // Step 4: the cut of least cost among those that explain most of the
    // misfit and that the caller allows (ties: the smaller k).
    std::vector<size_t> candidates;
    for (size_t k = 1; k < n; ++k) {
      if (prefix[k] + suffix[k] < max_sse_ratio * sse_m2) candidates.push_back(k);
    }
    std::stable_sort(candidates.begin(), candidates.end(), [&](size_t x, size_t y) {
      return prefix[x] + suffix[x] < prefix[y] + suffix[y];
    });
    size_t best_k = 0;
    for (size_t k : candidates) {
      if (!cut_allowed) {
        best_k = k;
        break;
      }
      std::vector<uint32_t> head, tail;
      for (size_t i = 0; i < n; ++i) (i < k ? head : tail).push_back(keyed[i].second);
      if (cut_allowed(head, tail)) {
        best_k = k;
        break;
      }
    }
    if (best_k == 0) {
      std::sort(subset.begin(), subset.end());
      groups.push_back(std::move(subset));
      continue;
    }
    std::vector<uint32_t> first, rest;
    for (size_t k = 0; k < n; ++k) (k < best_k ? first : rest).push_back(keyed[k].second);
    stack.push_back(std::move(rest));
    stack.push_back(std::move(first));
  }
  return groups;
}

}  // namespace mapd::fusion
