#include "client/robot/split_and_merge.h"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <utility>

#include "geometry/line_fit.h"

namespace mapd::robot {
namespace {

using geometry::FitLine;
using geometry::Line2;
using geometry::PointMoments2;

struct Piece {
  size_t first;
  size_t last;  // inclusive
};

// Index of the point of [first, last] farthest from the chord first-last, and
// that distance. A degenerate chord (coincident ends) measures from the point.
std::pair<size_t, double> FarthestFromChord(const std::vector<Vec2>& points, size_t first,
                                            size_t last) {
  const Vec2& a = points[first];
  const Vec2 d = points[last] - a;
  const double len = d.norm();
  size_t best = first;
  double best_m = -1.0;
  for (size_t i = first + 1; i < last; ++i) {
    const Vec2 r = points[i] - a;
    const double dist = len > 0.0 ? std::abs(d.x() * r.y() - d.y() * r.x()) / len : r.norm();
    if (dist > best_m) {
      best_m = dist;
      best = i;
    }
  }
  return {best, best_m};
}

// Step 2: recursive split of one run, in order (explicit stack: runs can be long).
void Split(const std::vector<Vec2>& points, Piece run, const SplitAndMergeParams& params,
           std::vector<Piece>* out) {
  std::vector<Piece> stack = {run};
  while (!stack.empty()) {
    const Piece p = stack.back();
    stack.pop_back();
    if (p.last - p.first >= 2) {
      const auto [k, dist_m] = FarthestFromChord(points, p.first, p.last);
      if (dist_m > params.split_m) {
        // The right half is processed second; the break point k ends the left one.
        stack.push_back({params.split_point_in_both ? k : k + 1, p.last});
        stack.push_back({p.first, k});
        continue;
      }
    }
    out->push_back(p);
  }
}

// The foot of the perpendicular from p to `line`.
Vec2 Project(const Line2& line, const Vec2& p) {
  return line.point + (p - line.point).dot(line.direction) * line.direction;
}

}  // namespace

std::vector<ExtractedLine> SplitAndMerge(const std::vector<Vec2>& points,
                                         const SplitAndMergeParams& params) {
  // Steps 1 and 2: runs without gaps, each split.
  std::vector<Piece> pieces;
  std::vector<size_t> run_of;  // run index of each piece: merging stays inside a run
  size_t run_count = 0;
  const auto continues = [&](const Vec2& p, const Vec2& q) {
    if (!q.allFinite()) return false;
    const double range_m = params.gap_from_farther_point ? std::max(p.norm(), q.norm()) : q.norm();
    const double limit = params.max_gap_m + params.gap_per_range * range_m;
    return (q - p).norm() <= limit;
  };
  for (size_t start = 0; start < points.size();) {
    if (!points[start].allFinite()) {
      ++start;
      continue;
    }
    size_t end = start;
    while (end + 1 < points.size() && continues(points[end], points[end + 1])) ++end;
    Split(points, {start, end}, params, &pieces);
    run_of.resize(pieces.size(), run_count);
    ++run_count;
    start = end + 1;
  }

  // Step 3: merge neighbours of one run while the joined piece stays straight
  // (the pieces of a run tile it in order, sharing the break point or not).
  std::vector<Piece> merged;
  for (size_t i = 0; i < pieces.size(); ++i) {
    if (params.merge_neighbours && !merged.empty() && run_of[i] == run_of[i - 1]) {
      const Piece joined{merged.back().first, pieces[i].last};
      if (FarthestFromChord(points, joined.first, joined.last).second <= params.split_m) {
        merged.back() = joined;
        continue;
      }
    }
    merged.push_back(pieces[i]);
  }

  // Step 4: fit, clip, filter.
  std::vector<ExtractedLine> lines;
  for (const Piece& p : merged) {
    if (p.last - p.first + 1 < params.min_points) continue;
    PointMoments2 moments;
    for (size_t i = p.first; i <= p.last; ++i) moments.Add(points[i]);
    const Line2 line = FitLine(moments);
    ExtractedLine out;
    out.segment =
        params.clip_to_extremes
            ? ExtremeProjections(
                  line, std::vector<Vec2>(points.begin() + static_cast<std::ptrdiff_t>(p.first),
                                          points.begin() + static_cast<std::ptrdiff_t>(p.last) + 1))
            : Segment2{Project(line, points[p.first]), Project(line, points[p.last])};
    if (out.segment.length() < params.min_length_m) continue;
    out.first = p.first;
    out.last = p.last;
    // The smallest eigenvalue of the scatter is the sum of squared orthogonal distances.
    const Eigen::Matrix2d& s = moments.scatter;
    const double half_trace = 0.5 * (s(0, 0) + s(1, 1));
    const double radius = std::hypot(0.5 * (s(0, 0) - s(1, 1)), s(0, 1));
    out.rms_m = std::sqrt(std::max(0.0, half_trace - radius) / static_cast<double>(moments.count));
    lines.push_back(out);
  }
  return lines;
}

}  // namespace mapd::robot
