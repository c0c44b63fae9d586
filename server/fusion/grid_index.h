// A uniform grid hash over the ground plane, for the engine's neighbour
// queries (feature centres, published endpoints). Header-only: small and generic.
#ifndef MAPD_FUSION_GRID_INDEX_H_
#define MAPD_FUSION_GRID_INDEX_H_

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <unordered_map>
#include <utility>
#include <vector>

#include "geometry/segment2.h"

namespace mapd::fusion {

struct CellKey {
  int64_t x = 0;
  int64_t y = 0;
  bool operator==(const CellKey& o) const { return x == o.x && y == o.y; }
};

struct CellKeyHash {
  size_t operator()(const CellKey& k) const {
    const uint64_t h = static_cast<uint64_t>(k.x) * 0x9E3779B97F4A7C15ULL ^
                       (static_cast<uint64_t>(k.y) + 0x632BE59BD9B4E019ULL);
    return static_cast<size_t>(h ^ (h >> 29));
  }
};

// Items of type T filed under the cell that contains their point.
template <typename T>
class UniformGrid {
 public:
  // REQUIRES: cell_m > 0 and finite. Coordinates are bounded by the engine's
  // input check (|x| <= 1e6 m), so cell indices fit easily in int64.
  explicit UniformGrid(double cell_m) : cell_m_(cell_m) {}

  CellKey KeyOf(const geometry::Vec2& p) const {
    return {static_cast<int64_t>(std::floor(p.x() / cell_m_)),
            static_cast<int64_t>(std::floor(p.y() / cell_m_))};
  }

  void Insert(const geometry::Vec2& p, T item) { cells_[KeyOf(p)].push_back(std::move(item)); }

  // Removes the items filed at p for which pred(item) holds (order not kept).
  template <typename Pred>
  void EraseIf(const geometry::Vec2& p, Pred pred) {
    auto it = cells_.find(KeyOf(p));
    if (it == cells_.end()) return;
    std::vector<T>& items = it->second;
    for (size_t i = 0; i < items.size();) {
      if (pred(items[i])) {
        items[i] = std::move(items.back());
        items.pop_back();
      } else {
        ++i;
      }
    }
    if (items.empty()) cells_.erase(it);
  }

  // Calls fn(item) for every item in the cells that meet the square of half
  // width radius_m around p (a superset of the disc: callers filter by distance).
  template <typename Fn>
  void ForEachNear(const geometry::Vec2& p, double radius_m, Fn&& fn) const {
    const CellKey lo = KeyOf(p - geometry::Vec2(radius_m, radius_m));
    const CellKey hi = KeyOf(p + geometry::Vec2(radius_m, radius_m));
    const double box_cells =
        static_cast<double>(hi.x - lo.x + 1) * static_cast<double>(hi.y - lo.y + 1);
    if (box_cells > static_cast<double>(cells_.size())) {
      // A huge query (long feature, large threshold): scanning the occupied
      // cells is cheaper than probing empty ones.
      for (const auto& [key, items] : cells_) {
        if (key.x < lo.x || key.x > hi.x || key.y < lo.y || key.y > hi.y) continue;
        for (const T& item : items) fn(item);
      }
      return;
    }
    for (int64_t x = lo.x; x <= hi.x; ++x) {
      for (int64_t y = lo.y; y <= hi.y; ++y) {
        auto it = cells_.find({x, y});
        if (it == cells_.end()) continue;
        for (const T& item : it->second) fn(item);
      }
    }
  }

  // Calls fn(item) for every item in the cells that come within radius_m of
  // segment s (a superset of the items within radius_m of s: callers filter).
  // For a long segment this probes a thin band of cells, not the square
  // around its whole length that ForEachNear would.
  template <typename Fn>
  void ForEachNearSegment(const geometry::Segment2& s, double radius_m, Fn&& fn) const {
    const geometry::Vec2 r(radius_m, radius_m);
    const CellKey lo = KeyOf(s.a.cwiseMin(s.b) - r);
    const CellKey hi = KeyOf(s.a.cwiseMax(s.b) + r);
    const double box_cells =
        static_cast<double>(hi.x - lo.x + 1) * static_cast<double>(hi.y - lo.y + 1);
    // A cell meets the band if its centre is within radius + half its diagonal.
    const double reach_m = radius_m + 0.7072 * cell_m_;
    // geometry::PointSegmentDistance's arithmetic, with the segment's terms
    // computed once: the same cells, without a call per cell.
    const geometry::Vec2 d = s.direction();
    const double len2 = d.squaredNorm();
    const auto beyond = [&](const geometry::Vec2& p) {
      if (len2 == 0.0) return (p - s.a).norm() > reach_m;
      const double t = std::clamp((p - s.a).dot(d) / len2, 0.0, 1.0);
      return (p - (s.a + t * d)).norm() > reach_m;
    };
    if (box_cells > static_cast<double>(cells_.size())) {
      for (const auto& [key, items] : cells_) {
        if (key.x < lo.x || key.x > hi.x || key.y < lo.y || key.y > hi.y) continue;
        if (beyond(CentreOf(key))) continue;
        for (const T& item : items) fn(item);
      }
      return;
    }
    for (int64_t x = lo.x; x <= hi.x; ++x) {
      for (int64_t y = lo.y; y <= hi.y; ++y) {
        if (beyond(CentreOf({x, y}))) continue;
        auto it = cells_.find({x, y});
        if (it == cells_.end()) continue;
        for (const T& item : it->second) fn(item);
      }
    }
  }

 private:
  geometry::Vec2 CentreOf(const CellKey& k) const {
    return {(static_cast<double>(k.x) + 0.5) * cell_m_, (static_cast<double>(k.y) + 0.5) * cell_m_};
  }

  double cell_m_;
  std::unordered_map<CellKey, std::vector<T>, CellKeyHash> cells_;
};

}  // namespace mapd::fusion

#endif  // MAPD_FUSION_GRID_INDEX_H_
