#include "eval/baselines/density_fuser.h"

#include <algorithm>
#include <cmath>
#include <utility>

#include "fusion/grid_index.h"

namespace mapd::fusion::baselines {

using geometry::Segment2;
using geometry::Vec2;

namespace {

constexpr double kCellM = 2.0;  // midpoint grid for the neighbour search

double LineDistance(const Vec2& p, const Segment2& s) {
  const Vec2 u = s.direction().normalized();
  const Vec2 d = p - s.a;
  return std::abs(u.x() * d.y() - u.y() * d.x());
}

}  // namespace

bool DensityNeighbours(const Segment2& f, const Segment2& g, double lateral_m,
                       double min_overlap_m) {
  const double lateral = std::max(LineDistance(f.midpoint(), g), LineDistance(g.midpoint(), f));
  if (lateral > lateral_m) return false;
  AxialMean mean;
  mean.Add(f, 1.0);
  mean.Add(g, 1.0);
  const Vec2 u = mean.Direction();
  const double fa = f.a.dot(u), fb = f.b.dot(u), ga = g.a.dot(u), gb = g.b.dot(u);
  const double overlap =
      std::min(std::max(fa, fb), std::max(ga, gb)) - std::max(std::min(fa, fb), std::min(ga, gb));
  return overlap >= min_overlap_m;
}

std::vector<std::vector<uint32_t>> DensityFuser::Cluster(const std::vector<Member>& members) const {
  std::vector<std::vector<uint32_t>> clusters;
  for (const std::vector<uint32_t>& group : OrientationGroups(members, params_.orientation)) {
    UniformGrid<uint32_t> grid(kCellM);
    double max_half_m = 0.0;
    for (uint32_t i : group) {
      const Segment2& s = members[i].feature.segment;
      grid.Insert(s.midpoint(), i);
      max_half_m = std::max(max_half_m, 0.5 * s.length());
    }
    const auto neighbours = [&](uint32_t i, std::vector<uint32_t>* out) {
      out->clear();
      const Segment2& s = members[i].feature.segment;
      const double reach = 0.5 * s.length() + max_half_m + params_.lateral_m +
                           std::max(0.0, -params_.min_overlap_m) + 1e-6;
      grid.ForEachNear(s.midpoint(), reach, [&](uint32_t j) {
        if (DensityNeighbours(s, members[j].feature.segment, params_.lateral_m,
                              params_.min_overlap_m)) {
          out->push_back(j);  // includes i itself
        }
      });
      std::sort(out->begin(), out->end());
    };
    // DBSCAN, visiting segments in index order (deterministic).
    std::unordered_map<uint32_t, int> label;  // -1 noise, >= 0 cluster
    std::vector<uint32_t> seeds, found;
    for (uint32_t i : group) {
      if (label.count(i) != 0) continue;
      neighbours(i, &found);
      if (found.size() < params_.min_pts) {
        label[i] = -1;
        continue;
      }
      const int c = static_cast<int>(clusters.size());
      clusters.emplace_back();
      label[i] = c;
      clusters.back().push_back(i);
      seeds = found;
      for (size_t k = 0; k < seeds.size(); ++k) {
        const uint32_t j = seeds[k];
        auto it = label.find(j);
        if (it != label.end() && it->second >= 0) continue;
        const bool was_noise = it != label.end();
        label[j] = c;
        clusters[static_cast<size_t>(c)].push_back(j);
        if (was_noise) continue;  // a border point: not expanded
        neighbours(j, &found);
        if (found.size() >= params_.min_pts) seeds.insert(seeds.end(), found.begin(), found.end());
      }
    }
    for (uint32_t i : group) {
      if (label[i] < 0) clusters.push_back({i});
    }
  }
  for (std::vector<uint32_t>& c : clusters) std::sort(c.begin(), c.end());
  return clusters;
}

geometry::Line2 DensityFuser::MergeLine(const std::vector<Member>& members,
                                        const std::vector<uint32_t>& cluster) const {
  AxialMean orientation;
  Vec2 middle = Vec2::Zero();
  double total = 0.0;
  for (uint32_t i : cluster) {
    const Segment2& s = members[i].feature.segment;
    const double w = s.length();
    orientation.Add(s, w);
    middle += w * s.midpoint();
    total += w;
  }
  geometry::Line2 line;
  line.point = middle / total;
  line.direction = geometry::CanonicalDirection(orientation.Direction());
  return line;
}

}  // namespace mapd::fusion::baselines
