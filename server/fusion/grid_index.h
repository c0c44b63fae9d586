// A uniform grid hash over the ground plane, for the engine's neighbour
// queries (feature centres, published endpoints). Header-only: small and generic.
#ifndef MAPD_FUSION_GRID_INDEX_H_
#define MAPD_FUSION_GRID_INDEX_H_

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <unordered_map>
#include <utility>
#include <vector>

#include "fusion/floor_int.h"
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

// Cell -> items, by open addressing (linear probing, a power-of-two table at
// most half full, backward-shift erase). The engine's queries probe many empty
// cells; std::unordered_map spends a division and a bucket load on each miss
// (a sixth of the fuser's time in a city soak), this a mask and one slot.
template <typename T>
class CellTable {
 public:
  size_t size() const { return size_; }

  const std::vector<T>* Find(const CellKey& key) const {
    if (size_ == 0) return nullptr;
    for (size_t i = Home(key);; i = (i + 1) & mask_) {
      const Slot& slot = slots_[i];
      if (slot.items == kEmpty) return nullptr;
      if (slot.key == key) return &items_[slot.items];
    }
  }
  std::vector<T>* Find(const CellKey& key) {
    return const_cast<std::vector<T>*>(static_cast<const CellTable&>(*this).Find(key));
  }

  std::vector<T>& FindOrAdd(const CellKey& key) {
    if (2 * (size_ + 1) > slots_.size()) Grow();
    size_t i = Home(key);
    for (; slots_[i].items != kEmpty; i = (i + 1) & mask_) {
      if (slots_[i].key == key) return items_[slots_[i].items];
    }
    uint32_t index;
    if (free_.empty()) {
      index = static_cast<uint32_t>(items_.size());
      items_.emplace_back();
    } else {
      index = free_.back();
      free_.pop_back();
    }
    slots_[i] = {key, index};
    ++size_;
    return items_[index];
  }

  // REQUIRES: the cell is present and its items empty.
  void Erase(const CellKey& key) {
    size_t i = Home(key);
    while (!(slots_[i].key == key)) i = (i + 1) & mask_;
    free_.push_back(slots_[i].items);
    // Backward shift: move later entries of the probe run into the hole, so
    // lookups never need tombstones.
    for (size_t j = (i + 1) & mask_; slots_[j].items != kEmpty; j = (j + 1) & mask_) {
      const size_t home = Home(slots_[j].key);
      // Whether j's home lies cyclically in (i, j]: then it stays.
      const bool stays = i <= j ? (i < home && home <= j) : (i < home || home <= j);
      if (stays) continue;
      slots_[i] = slots_[j];
      i = j;
    }
    slots_[i].items = kEmpty;
    --size_;
  }

  // fn(key, items) for every cell, in table order.
  template <typename Fn>
  void ForEach(Fn&& fn) const {
    for (const Slot& slot : slots_) {
      if (slot.items != kEmpty) fn(slot.key, items_[slot.items]);
    }
  }

 private:
  static constexpr uint32_t kEmpty = UINT32_MAX;
  struct Slot {
    CellKey key;
    uint32_t items = kEmpty;  // index into items_
  };

  size_t Home(const CellKey& key) const {
    uint64_t h = static_cast<uint64_t>(key.x) * 0x9E3779B97F4A7C15ULL ^
                 static_cast<uint64_t>(key.y) * 0xC2B2AE3D27D4EB4FULL;
    h ^= h >> 32;
    return static_cast<size_t>(h) & mask_;
  }

  void Grow() {
    std::vector<Slot> old = std::move(slots_);
    slots_.assign(old.empty() ? 64 : 2 * old.size(), Slot());
    mask_ = slots_.size() - 1;
    for (const Slot& slot : old) {
      if (slot.items == kEmpty) continue;
      size_t i = Home(slot.key);
      while (slots_[i].items != kEmpty) i = (i + 1) & mask_;
      slots_[i] = slot;
    }
  }

  std::vector<Slot> slots_;
  size_t mask_ = 0;
  size_t size_ = 0;
  std::vector<std::vector<T>> items_;  // by slot index; reused through free_
  std::vector<uint32_t> free_;
};

// Items of type T filed under the cell that contains their point.
template <typename T>
class UniformGrid {
 public:
  // REQUIRES: cell_m > 0 and finite. Coordinates are bounded by the engine's
  // input check (|x| <= 1e6 m), so cell indices fit easily in int64.
  explicit UniformGrid(double cell_m) : cell_m_(cell_m) {}

  CellKey KeyOf(const geometry::Vec2& p) const {
    return {FloorInt(p.x() / cell_m_), FloorInt(p.y() / cell_m_)};
  }

  void Insert(const geometry::Vec2& p, T item) {
    cells_.FindOrAdd(KeyOf(p)).push_back(std::move(item));
  }

  // Items filed in the cell that contains p.
  size_t CountAt(const geometry::Vec2& p) const {
    const std::vector<T>* items = cells_.Find(KeyOf(p));
    return items == nullptr ? 0 : items->size();
  }

  // Removes the items filed at p for which pred(item) holds (order not kept).
  template <typename Pred>
  void EraseIf(const geometry::Vec2& p, Pred pred) {
    const CellKey key = KeyOf(p);
    std::vector<T>* found = cells_.Find(key);
    if (found == nullptr) return;
    std::vector<T>& items = *found;
    for (size_t i = 0; i < items.size();) {
      if (pred(items[i])) {
        items[i] = std::move(items.back());
        items.pop_back();
      } else {
        ++i;
      }
    }
    if (items.empty()) cells_.Erase(key);
  }

  // Calls fn(item) for every item in the cells that meet the square of half
  // width radius_m around p (a superset of the disc: callers filter by
  // distance). At most max_items items: whole cells, in ascending (x, y)
  // order, up to the first cell that would take the count past it; so which
  // items are visited depends on what is filed where, not on the order it
  // was filed in. Returns false if cells were left out.
  template <typename Fn>
  bool ForEachNear(const geometry::Vec2& p, double radius_m, Fn&& fn,
                   size_t max_items = SIZE_MAX) const {
    const CellKey lo = KeyOf(p - geometry::Vec2(radius_m, radius_m));
    const CellKey hi = KeyOf(p + geometry::Vec2(radius_m, radius_m));
    return VisitCells(
        lo, hi, [](const CellKey&) { return true; }, fn, max_items);
  }

  // The cells within radius_m of a segment (a superset of the cells holding
  // points within radius_m of it): those of the box around the segment
  // grown by radius_m whose centre lies within radius_m plus half a cell
  // diagonal of it. Meets() is the test ForEachNearSegment applies to every
  // cell it probes, so a caller holding a list of items' points can tell
  // which of them a search would find without searching.
  struct SegmentBand {
    CellKey lo, hi;  // the box, inclusive
    geometry::Vec2 a, d;
    double len2 = 0.0, reach2 = 0.0, cell_m = 1.0;
    bool Meets(const CellKey& key) const {
      if (key.x < lo.x || key.x > hi.x || key.y < lo.y || key.y > hi.y) return false;
      return Near(key);
    }
    // Meets() inside the box.
    bool Near(const CellKey& key) const {
      // geometry::PointSegmentDistance's arithmetic, with the segment's terms
      // computed once: no call and no root per cell.
      const geometry::Vec2 c((static_cast<double>(key.x) + 0.5) * cell_m,
                             (static_cast<double>(key.y) + 0.5) * cell_m);
      if (len2 == 0.0) return (c - a).squaredNorm() <= reach2;
      const double t = std::clamp((c - a).dot(d) / len2, 0.0, 1.0);
      return (c - (a + t * d)).squaredNorm() <= reach2;
    }
  };
  SegmentBand BandOf(const geometry::Segment2& s, double radius_m) const {
    const geometry::Vec2 r(radius_m, radius_m);
    SegmentBand band;
    band.lo = KeyOf(s.a.cwiseMin(s.b) - r);
    band.hi = KeyOf(s.a.cwiseMax(s.b) + r);
    band.a = s.a;
    band.d = s.direction();
    band.len2 = band.d.squaredNorm();
    // A cell meets the band if its centre is within radius + half its diagonal.
    const double reach_m = radius_m + 0.7072 * cell_m_;
    band.reach2 = reach_m * reach_m;
    band.cell_m = cell_m_;
    return band;
  }

  // Calls fn(item) for every item in the cells that come within radius_m of
  // segment s (BandOf; a superset of the items within radius_m of s: callers
  // filter), at most max_items as ForEachNear. For a long segment this probes
  // a thin band of cells, not the square around its whole length that
  // ForEachNear would.
  template <typename Fn>
  bool ForEachNearSegment(const geometry::Segment2& s, double radius_m, Fn&& fn,
                          size_t max_items = SIZE_MAX) const {
    return ForEachInBand(BandOf(s, radius_m), fn, max_items);
  }
  template <typename Fn>
  bool ForEachInBand(const SegmentBand& band, Fn&& fn, size_t max_items = SIZE_MAX) const {
    return VisitCells(
        band.lo, band.hi, [&band](const CellKey& key) { return band.Near(key); }, fn, max_items);
  }

 private:
  // The cells of the box [lo, hi] for which wanted(key) holds, in ascending
  // (x, y) order, whole, while the item count stays within max_items.
  template <typename Wanted, typename Fn>
  bool VisitCells(const CellKey& lo, const CellKey& hi, const Wanted& wanted, Fn& fn,
                  size_t max_items) const {
    size_t visited = 0;
    const auto visit = [&](const std::vector<T>& items) {
      if (items.size() > max_items - visited) return false;
      visited += items.size();
      for (const T& item : items) fn(item);
      return true;
    };
    const double box_cells =
        static_cast<double>(hi.x - lo.x + 1) * static_cast<double>(hi.y - lo.y + 1);
    if (box_cells > static_cast<double>(cells_.size())) {
      // A huge query (long feature, large threshold): scanning the occupied
      // cells is cheaper than probing empty ones; sorted, so that a cut-off
      // falls where it would in the probing order below.
      std::vector<std::pair<CellKey, const std::vector<T>*>> hits;
      cells_.ForEach([&](const CellKey& key, const std::vector<T>& items) {
        if (key.x < lo.x || key.x > hi.x || key.y < lo.y || key.y > hi.y) return;
        if (!wanted(key)) return;
        if (max_items == SIZE_MAX) {
          for (const T& item : items) fn(item);  // no cut-off: any order will do
        } else {
          hits.emplace_back(key, &items);
        }
      });
      std::sort(hits.begin(), hits.end(), [](const auto& u, const auto& v) {
        return u.first.x != v.first.x ? u.first.x < v.first.x : u.first.y < v.first.y;
      });
      for (const auto& hit : hits) {
        if (!visit(*hit.second)) return false;
      }
      return true;
    }
    for (int64_t x = lo.x; x <= hi.x; ++x) {
      for (int64_t y = lo.y; y <= hi.y; ++y) {
        const CellKey key{x, y};
        if (!wanted(key)) continue;
        const std::vector<T>* items = cells_.Find(key);
        if (items == nullptr) continue;
        if (!visit(*items)) return false;
      }
    }
    return true;
  }

  double cell_m_;
  CellTable<T> cells_;
};

}  // namespace mapd::fusion

#endif  // MAPD_FUSION_GRID_INDEX_H_
