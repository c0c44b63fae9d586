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
    BatchCluster c;
    std::vector<Vec2> endpoints;
    std::set<ObservationId> support;
    for (size_t i : component) {
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
