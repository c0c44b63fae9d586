#include "fusion/batch_reference.h"

#include <algorithm>
#include <cmath>
#include <queue>
#include <set>

#include <Eigen/Eigenvalues>

#include "fusion/criteria.h"

namespace mapd::fusion::testing {
namespace {

using geometry::Segment2;
using geometry::Vec2;

struct Flat {
  GroundFeature feature;
  ObservationId observation;
};

struct Fit {
  Vec2 point;
  Vec2 direction;
};

Fit FitEndpoints(const std::vector<Vec2>& points) {
  Vec2 mean = Vec2::Zero();
  for (const Vec2& p : points) mean += p;
  mean /= static_cast<double>(points.size());
  Eigen::Matrix2d scatter = Eigen::Matrix2d::Zero();
  for (const Vec2& p : points) scatter += (p - mean) * (p - mean).transpose();
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eig(scatter);
  return {mean, eig.eigenvectors().col(1).normalized()};  // largest eigenvalue last
}

Vec2 Joint(const Vec2& p, const Fit& lp, const Vec2& q, const Fit& lq, const FusionParams& params) {
  const Vec2 mid = (p + q) / 2.0;
  if (params.corner_mode == CornerMode::kMidpoint) return mid;
  const double angle = std::acos(std::min(1.0, std::abs(lp.direction.dot(lq.direction))));
  if (angle <= 10.0 * 3.14159265358979323846 / 180.0) return mid;
  // lp.point + t * lp.direction = lq.point + s * lq.direction
  Eigen::Matrix2d a;
  a.col(0) = lp.direction;
  a.col(1) = -lq.direction;
  const Eigen::Vector2d ts = a.colPivHouseholderQr().solve(lq.point - lp.point);
  const Vec2 x = lp.point + ts(0) * lp.direction;
  if ((x - p).norm() > params.snap_m || (x - q).norm() > params.snap_m) return mid;
  return x;
}

// Sum of squared orthogonal distances of `points` to their TLS line: the
// smaller eigenvalue of the scatter about the mean.
double Sse(const std::vector<Vec2>& points) {
  Vec2 mean = Vec2::Zero();
  for (const Vec2& p : points) mean += p;
  mean /= static_cast<double>(points.size());
  Eigen::Matrix2d scatter = Eigen::Matrix2d::Zero();
  for (const Vec2& p : points) scatter += (p - mean) * (p - mean).transpose();
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eig(scatter);
  return eig.eigenvalues()(0);  // ascending
}

std::vector<Vec2> EndpointsOf(const std::vector<Flat>& all, const std::vector<size_t>& members) {
  std::vector<Vec2> points;
  for (size_t i : members) {
    points.push_back(all[i].feature.segment.a);
    points.push_back(all[i].feature.segment.b);
  }
  return points;
}

// The chain guard's rule (fusion/chain_guard.h), literally and recursively:
// appends the groups of `members` (indices into `all`) to `groups`.
void GuardGroups(const std::vector<Flat>& all, const std::vector<size_t>& members,
                 const FusionParams& params, std::vector<std::vector<size_t>>* groups) {
  const std::vector<Vec2> points = EndpointsOf(all, members);
  const double sse = Sse(points);
  const double rms = std::sqrt(std::max(0.0, sse) / static_cast<double>(points.size()));
  if (params.chain_max_rms_m == 0.0 || members.size() < 2 || rms <= params.chain_max_rms_m) {
    groups->push_back(members);
    return;
  }
  // Order along the fitted direction, its sign fixed by the reference
  // direction at 0.3 rad; ties by feature id.
  Fit fit = FitEndpoints(points);
  if (fit.direction.dot(Vec2(std::cos(0.3), std::sin(0.3))) < 0.0) fit.direction = -fit.direction;
  std::vector<size_t> order = members;
  const auto key = [&](size_t i) {
    return (all[i].feature.segment.midpoint() - fit.point).dot(fit.direction);
  };
  std::sort(order.begin(), order.end(), [&](size_t x, size_t y) {
    if (key(x) != key(y)) return key(x) < key(y);
    return all[x].feature.id < all[y].feature.id;
  });
  size_t best_k = 0;
  double best_cost = 0.0;
  for (size_t k = 1; k < order.size(); ++k) {
    const std::vector<size_t> head(order.begin(), order.begin() + static_cast<long>(k));
    const std::vector<size_t> tail(order.begin() + static_cast<long>(k), order.end());
    const double cost = std::max(0.0, Sse(EndpointsOf(all, head))) +
                        std::max(0.0, Sse(EndpointsOf(all, tail)));
    if (best_k == 0 || cost < best_cost) {
      best_k = k;
      best_cost = cost;
    }
  }
  if (!(best_cost < params.chain_max_sse_ratio * sse)) {
    groups->push_back(members);
    return;
  }
  GuardGroups(all, std::vector<size_t>(order.begin(), order.begin() + static_cast<long>(best_k)),
              params, groups);
  GuardGroups(all, std::vector<size_t>(order.begin() + static_cast<long>(best_k), order.end()),
              params, groups);
}

}  // namespace

std::vector<BatchCluster> BatchFuse(const std::vector<BatchObservation>& observations,
                                    const FusionParams& params) {
  std::vector<Flat> all;
  for (const BatchObservation& o : observations) {
    for (const GroundFeature& f : o.features) all.push_back({f, o.id});
  }
  const size_t n = all.size();
  std::vector<std::vector<size_t>> adjacent(n);
  for (size_t i = 0; i < n; ++i) {
    for (size_t j = i + 1; j < n; ++j) {
      if (all[i].observation == all[j].observation) continue;
      if (!MeetsAllCriteria(all[i].feature.segment, all[j].feature.segment, params)) continue;
      adjacent[i].push_back(j);
      adjacent[j].push_back(i);
    }
  }

  std::vector<BatchCluster> clusters;
  std::vector<Fit> fits;
  std::vector<bool> seen(n, false);
  for (size_t start = 0; start < n; ++start) {
    if (seen[start]) continue;
    std::vector<size_t> component;
    std::queue<size_t> queue;
    queue.push(start);
    seen[start] = true;
    while (!queue.empty()) {
      const size_t i = queue.front();
      queue.pop();
      component.push_back(i);
      for (size_t j : adjacent[i]) {
        if (!seen[j]) {
          seen[j] = true;
          queue.push(j);
        }
      }
    }
    std::vector<std::vector<size_t>> groups;
    GuardGroups(all, component, params, &groups);
    for (const std::vector<size_t>& group : groups) {
      BatchCluster c;
      std::vector<Vec2> endpoints;
      std::set<ObservationId> support;
      for (size_t i : group) {
        c.members.push_back(all[i].feature.id);
        endpoints.push_back(all[i].feature.segment.a);
        endpoints.push_back(all[i].feature.segment.b);
        support.insert(all[i].observation);
      }
      std::sort(c.members.begin(), c.members.end());
      c.id = c.members.front();
      c.support = static_cast<uint32_t>(support.size());
      c.published = c.support >= params.min_support;
      const Fit fit = FitEndpoints(endpoints);
      double t_min = 1e300, t_max = -1e300;
      for (const Vec2& p : endpoints) {
        t_min = std::min(t_min, (p - fit.point).dot(fit.direction));
        t_max = std::max(t_max, (p - fit.point).dot(fit.direction));
      }
      c.fitted = {fit.point + t_min * fit.direction, fit.point + t_max * fit.direction};
      c.segment = c.fitted;
      clusters.push_back(c);
      fits.push_back(fit);
    }
  }

  // Corner rule: mutual nearest endpoints of different published features.
  struct End {
    size_t cluster;
    int end;
    Vec2 p;
  };
  std::vector<End> ends;
  for (size_t k = 0; k < clusters.size(); ++k) {
    if (!clusters[k].published) continue;
    ends.push_back({k, 0, clusters[k].fitted.a});
    ends.push_back({k, 1, clusters[k].fitted.b});
  }
  const auto nearest = [&](size_t e) {
    long best = -1;
    for (size_t o = 0; o < ends.size(); ++o) {
      if (ends[o].cluster == ends[e].cluster) continue;
      const double d = (ends[o].p - ends[e].p).norm();
      if (!(d < params.snap_m)) continue;
      if (best < 0 || d < (ends[best].p - ends[e].p).norm()) best = static_cast<long>(o);
    }
    return best;
  };
  std::vector<Vec2> moved(ends.size());
  for (size_t e = 0; e < ends.size(); ++e) {
    moved[e] = ends[e].p;
    const long o = nearest(e);
    if (o < 0 || nearest(static_cast<size_t>(o)) != static_cast<long>(e)) continue;
    const End& other = ends[static_cast<size_t>(o)];
    moved[e] = Joint(ends[e].p, fits[ends[e].cluster], other.p, fits[other.cluster], params);
  }
  for (size_t e = 0; e < ends.size(); ++e) {
    Segment2& s = clusters[ends[e].cluster].segment;
    (ends[e].end == 0 ? s.a : s.b) = moved[e];
  }
  std::sort(clusters.begin(), clusters.end(),
            [](const BatchCluster& x, const BatchCluster& y) { return x.id < y.id; });
  return clusters;
}

}  // namespace mapd::fusion::testing
