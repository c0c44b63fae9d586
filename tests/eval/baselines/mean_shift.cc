#include "eval/baselines/mean_shift.h"

#include <algorithm>
#include <cmath>
#include <numeric>

#include "fusion/grid_index.h"

namespace mapd::fusion::baselines {

using geometry::Vec2;

namespace {

constexpr int kMaxIterations = 200;

// Wraps an axial difference into [-pi/2, pi/2).
double WrapAxial(double d) {
  d = std::fmod(d + 0.5 * M_PI, M_PI);
  if (d < 0.0) d += M_PI;
  return d - 0.5 * M_PI;
}

double Weight(Kernel kernel, double d, double h) {
  if (kernel == Kernel::kFlat) return d <= h ? 1.0 : 0.0;
  if (d > 3.0 * h) return 0.0;
  return std::exp(-0.5 * (d * d) / (h * h));
}

double Cutoff(Kernel kernel, double h) { return kernel == Kernel::kFlat ? h : 3.0 * h; }

}  // namespace

double AxialAngle(const geometry::Segment2& s) {
  const Vec2 d = s.direction();
  double theta = std::atan2(d.y(), d.x());
  if (theta < 0.0) theta += M_PI;
  if (theta >= M_PI) theta -= M_PI;
  return theta;
}

void AxialMean::Add(const geometry::Segment2& s, double weight) {
  const double theta = AxialAngle(s);
  c_ += weight * std::cos(2.0 * theta);
  s_ += weight * std::sin(2.0 * theta);
}

Vec2 AxialMean::Direction() const {
  const double theta = 0.5 * std::atan2(s_, c_);
  return Vec2(std::cos(theta), std::sin(theta));
}

Modes OrientationModes(const std::vector<double>& theta_rad, const std::vector<double>& weights,
                       const OrientationShiftParams& params) {
  const int bins = std::max(1, static_cast<int>(std::lround(M_PI / params.bin_rad)));
  const double bin_rad = M_PI / bins;
  std::vector<double> mass(static_cast<size_t>(bins), 0.0);
  std::vector<int> bin_of(theta_rad.size());
  for (size_t i = 0; i < theta_rad.size(); ++i) {
    int b = static_cast<int>(std::floor(theta_rad[i] / bin_rad));
    b = ((b % bins) + bins) % bins;
    bin_of[i] = b;
    mass[static_cast<size_t>(b)] += weights[i];
  }
  const double h = params.bandwidth_rad;
  const int reach = static_cast<int>(std::ceil(Cutoff(params.kernel, h) / bin_rad)) + 1;
  // Shift every occupied bin centre to its mode.
  std::vector<double> converged(static_cast<size_t>(bins), 0.0);
  for (int b = 0; b < bins; ++b) {
    if (mass[static_cast<size_t>(b)] == 0.0) continue;
    double x = (b + 0.5) * bin_rad;
    for (int it = 0; it < kMaxIterations; ++it) {
      const int centre = static_cast<int>(std::floor(x / bin_rad));
      double num = 0.0, den = 0.0;
      for (int k = centre - reach; k <= centre + reach; ++k) {
        const int kb = ((k % bins) + bins) % bins;
        const double m = mass[static_cast<size_t>(kb)];
        if (m == 0.0) continue;
        const double d = WrapAxial((kb + 0.5) * bin_rad - x);
        const double w = m * Weight(params.kernel, std::abs(d), h);
        num += w * d;
        den += w;
      }
      if (den == 0.0) break;
      const double step = num / den;
      x = std::fmod(x + step + M_PI, M_PI);
      if (std::abs(step) < 1e-4 * bin_rad) break;
    }
    converged[static_cast<size_t>(b)] = x;
  }
  // Group converged positions: modes closer than h / 2 are one.
  Modes out;
  std::vector<uint32_t> bin_label(static_cast<size_t>(bins), 0);
  for (int b = 0; b < bins; ++b) {
    if (mass[static_cast<size_t>(b)] == 0.0) continue;
    const double x = converged[static_cast<size_t>(b)];
    uint32_t label = static_cast<uint32_t>(out.mode.size());
    for (size_t m = 0; m < out.mode.size(); ++m) {
      if (std::abs(WrapAxial(out.mode[m] - x)) < 0.5 * h) {
        label = static_cast<uint32_t>(m);
        break;
      }
    }
    if (label == out.mode.size()) out.mode.push_back(x);
    bin_label[static_cast<size_t>(b)] = label;
  }
  out.label.resize(theta_rad.size());
  for (size_t i = 0; i < theta_rad.size(); ++i) {
    out.label[i] = bin_label[static_cast<size_t>(bin_of[i])];
  }
  return out;
}

std::vector<uint32_t> CentreModes(const std::vector<Vec2>& points, const CentreShiftParams& params,
                                  std::vector<Vec2>* modes) {
  modes->clear();
  std::vector<uint32_t> labels(points.size(), 0);
  if (points.empty()) return labels;
  const double h = params.bandwidth_m;
  const double cutoff = Cutoff(params.kernel, h);
  UniformGrid<uint32_t> grid(cutoff);
  for (size_t i = 0; i < points.size(); ++i) grid.Insert(points[i], static_cast<uint32_t>(i));

  // Seeds: mean of the points of each occupied h-cell, in a deterministic order.
  std::unordered_map<CellKey, std::pair<Vec2, int>, CellKeyHash> cells;
  UniformGrid<int> seed_grid(h);
  std::vector<CellKey> order;
  for (const Vec2& p : points) {
    const CellKey k = seed_grid.KeyOf(p);
    auto [it, inserted] = cells.try_emplace(k, Vec2::Zero(), 0);
    if (inserted) order.push_back(k);
    it->second.first += p;
    ++it->second.second;
  }
  std::sort(order.begin(), order.end(),
            [](const CellKey& a, const CellKey& b) { return a.x != b.x ? a.x < b.x : a.y < b.y; });

  struct Mode {
    Vec2 p;
    double density;
  };
  std::vector<Mode> found;
  for (const CellKey& k : order) {
    Vec2 x = cells[k].first / cells[k].second;
    double density = 0.0;
    for (int it = 0; it < kMaxIterations; ++it) {
      Vec2 num = Vec2::Zero();
      double den = 0.0;
      grid.ForEachNear(x, cutoff, [&](uint32_t i) {
        const double w = Weight(params.kernel, (points[i] - x).norm(), h);
        num += w * points[i];
        den += w;
      });
      if (den == 0.0) break;
      const Vec2 next = num / den;
      density = den;
      const double step = (next - x).norm();
      x = next;
      if (step < 1e-3 * h) break;
    }
    found.push_back({x, density});
  }
  // Denser modes first; drop modes within h of a kept one (sklearn's rule).
  std::stable_sort(found.begin(), found.end(),
                   [](const Mode& a, const Mode& b) { return a.density > b.density; });
  for (const Mode& m : found) {
    bool near = false;
    for (const Vec2& kept : *modes) near = near || (kept - m.p).norm() < h;
    if (!near) modes->push_back(m.p);
  }
  // Every point joins its nearest mode.
  for (size_t i = 0; i < points.size(); ++i) {
    double best = 0.0;
    for (size_t m = 0; m < modes->size(); ++m) {
      const double d = ((*modes)[m] - points[i]).squaredNorm();
      if (m == 0 || d < best) {
        best = d;
        labels[i] = static_cast<uint32_t>(m);
      }
    }
  }
  return labels;
}

}  // namespace mapd::fusion::baselines
