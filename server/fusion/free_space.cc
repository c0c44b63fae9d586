#include "fusion/free_space.h"

#include <algorithm>
#include <cmath>

namespace mapd::fusion {

using geometry::Segment2;
using geometry::Vec2;

namespace {

// Triangles thinner than this (twice the area, m^2) mark nothing: the origin
// lies on the segment's line, and no ray crossed anything.
constexpr double kMinDoubleAreaM2 = 1e-9;

int64_t FloorDiv(int64_t a, int64_t b) { return a >= 0 ? a / b : -((-a + b - 1) / b); }

int64_t CellIndex(double x) { return FloorInt(x / FreeSpaceGrid::kCellM); }

// One eroded half-plane of the triangle: inside iff n . p >= c.
struct HalfPlane {
  Vec2 n;
  double c;
};

HalfPlane Inward(const Vec2& p, const Vec2& q, double erosion_m) {
  const Vec2 d = q - p;
  const Vec2 n = Vec2(-d.y(), d.x()) / d.norm();  // left of p->q: inside for a ccw triangle
  return {n, n.dot(p) + erosion_m};
}

// The side of the triangle along the ray from the origin o through q, inside
// being on the left of p->q (p, q: the side's ends in counter-clockwise
// order, one of them o), eroded by k times the range along the ray:
// n . (x - o) >= k u . (x - o), i.e. (n - k u) . x >= (n - k u) . o.
HalfPlane InwardRay(const Vec2& p, const Vec2& q, const Vec2& o, double k) {
  const Vec2 d = q - p;
  const Vec2 n = Vec2(-d.y(), d.x()) / d.norm();
  const Vec2 far = p == o ? q : p;
  const Vec2 u = (far - o) / (far - o).norm();
  const Vec2 m = n - k * u;
  return {m, m.dot(o)};
}

// The x-range of triangle (o, a, b) within the horizontal band y0 <= y <= y1;
// false if they do not meet.
bool BandRange(const Vec2& o, const Vec2& a, const Vec2& b, double y0, double y1, double* x_min,
               double* x_max) {
  bool any = false;
  const auto take = [&](double x) {
    *x_min = any ? std::min(*x_min, x) : x;
    *x_max = any ? std::max(*x_max, x) : x;
    any = true;
  };
  const Vec2* corners[3] = {&o, &a, &b};
  for (int i = 0; i < 3; ++i) {
    const Vec2& p = *corners[i];
    const Vec2& q = *corners[(i + 1) % 3];
    if (p.y() >= y0 && p.y() <= y1) take(p.x());
    if (p.y() == q.y()) continue;
    for (const double y : {y0, y1}) {
      if ((y - p.y()) * (y - q.y()) < 0.0)
        take(p.x() + (y - p.y()) * (q.x() - p.x()) / (q.y() - p.y()));
    }
  }
  return any;
}

// AddView tests rows this many at a time for cells it would change (a
// divisor of kTileCells): on the CPU guard's city, 8 took the fewest
// instructions (valgrind), 4, 16 and 32 up to 6 % more.
constexpr int64_t kStripRows = 8;

// Where the boundary lines of two half-planes cross; false if parallel.
bool Crossing(const HalfPlane& g, const HalfPlane& h, Vec2* x) {
  const double det = g.n.x() * h.n.y() - g.n.y() * h.n.x();
  if (std::abs(det) < 1e-12) return false;
  *x = Vec2((g.c * h.n.y() - g.n.y() * h.c) / det, (g.n.x() * h.c - g.c * h.n.x()) / det);
  return true;
}

// The corners of the region inside all three half-planes of a view (side,
// segment, side), if it is the triangle they bound: false when erosion
// emptied it or turned it over (a view of a short segment far away).
bool ErodedCorners(const HalfPlane (&planes)[3], Vec2 (&corners)[3]) {
  constexpr double kToleranceM = 1e-9;
  for (int i = 0; i < 3; ++i) {
    if (!Crossing(planes[i], planes[(i + 1) % 3], &corners[i])) return false;
  }
  // Each corner inside the third plane, and the corners counter-clockwise.
  for (int i = 0; i < 3; ++i) {
    const HalfPlane& third = planes[(i + 2) % 3];
    if (third.n.dot(corners[i]) < third.c - kToleranceM) return false;
  }
  return geometry::Cross(corners[1] - corners[0], corners[2] - corners[0]) > 0.0;
}

}  // namespace

bool FreeSpaceGrid::Quiet(int64_t ty, size_t row_first, size_t row_last, int64_t cx_first,
                          int64_t cx_last) const {
  for (int64_t tx = FloorDiv(cx_first, kTileCells); tx * kTileCells <= cx_last; ++tx) {
    const TileData* found = tiles_.Find(TileKey(tx, ty));
    if (found == nullptr) return false;  // counts of zero
    const TileData& tile = *found;
    const int first = static_cast<int>(std::max(cx_first, tx * kTileCells) - tx * kTileCells);
    const int last =
        static_cast<int>(std::min(cx_last, (tx + 1) * kTileCells - 1) - tx * kTileCells);
    const uint32_t run =
        (last == kTileCells - 1 ? ~0u : (1u << (last + 1)) - 1u) & ~((1u << first) - 1u);
    for (size_t row = row_first; row <= row_last; ++row) {
      if (((run & ~tile.saturated[row]) | (run & tile.watched[row])) != 0) return false;
    }
  }
  return true;
}

FreeSpaceGrid::TileData& FreeSpaceGrid::TileAt(int64_t tx, int64_t ty) {
  return tiles_.FindOrAdd(TileKey(tx, ty));
}

FreeSpaceGrid::TileData& FreeSpaceGrid::TileTable::FindOrAdd(uint64_t key) {
  if (2 * (size_ + 1) > slots_.size()) Grow();
  size_t i = Home(key);
  for (; slots_[i].tile != nullptr; i = (i + 1) & mask_) {
    if (slots_[i].key == key) return *slots_[i].tile;
  }
  storage_.push_back(std::make_unique<TileData>());
  slots_[i] = {key, storage_.back().get()};
  ++size_;
  return *slots_[i].tile;
}

void FreeSpaceGrid::TileTable::Grow() {
  std::vector<Slot> old = std::move(slots_);
  slots_.assign(old.empty() ? 64 : 2 * old.size(), Slot());
  mask_ = slots_.size() - 1;
  for (const Slot& slot : old) {
    if (slot.tile == nullptr) continue;
    size_t i = Home(slot.key);
    while (slots_[i].tile != nullptr) i = (i + 1) & mask_;
    slots_[i] = slot;
  }
}

void FreeSpaceGrid::AddView(const Vec2& origin, const Segment2& segment) {
  Vec2 a = segment.a, b = segment.b;
  const double twice_area = geometry::Cross(a - origin, b - origin);
  if (std::abs(twice_area) < kMinDoubleAreaM2) return;
  if (twice_area < 0.0) std::swap(a, b);  // (origin, a, b) counter-clockwise
  const HalfPlane planes[3] = {InwardRay(origin, a, origin, kSideErosionPerM),
                               Inward(a, b, kSegmentMarginM),
                               InwardRay(b, origin, origin, kSideErosionPerM)};
  // The triangle's bounding box, clipped to the evidence range.
  const double y_lo = std::max(std::min({origin.y(), a.y(), b.y()}), origin.y() - range_m_);
  const double y_hi = std::min(std::max({origin.y(), a.y(), b.y()}), origin.y() + range_m_);
  const double x_lo = std::max(std::min({origin.x(), a.x(), b.x()}), origin.x() - range_m_);
  const double x_hi = std::min(std::max({origin.x(), a.x(), b.x()}), origin.x() + range_m_);
  // Consecutive rows mostly fall in the same tiles: the tiles of the current
  // tile row are looked up once each (row_tiles_, by column from tx_base; a
  // column outside it, which rounding could give, is looked up directly).
  const int64_t tx_base = FloorDiv(CellIndex(x_lo), kTileCells);
  const int64_t tx_count = FloorDiv(CellIndex(x_hi), kTileCells) - tx_base + 1;
  bool has_row = false;
  int64_t row_ty = 0;
  // Rows whose centre lies in [y_lo, y_hi] (the others are outside the
  // triangle or the range).
  const int64_t cy_first = CeilInt(y_lo / kCellM - 0.5);
  const int64_t cy_last = FloorInt(y_hi / kCellM - 0.5);
  Vec2 corners[3];
  const bool eroded = ErodedCorners(planes, corners);
  for (int64_t cy = cy_first; cy <= cy_last; ++cy) {
    const int64_t strip_first = FloorDiv(cy, kStripRows) * kStripRows;
    if (skip_quiet_rows_ && (cy == cy_first || cy == strip_first)) {
      // A new strip of rows (within one tile row): its rows are skipped
      // together if every cell the triangle could cover in them (its x-range
      // over the rows' centres) is saturated and unwatched, so that the rows
      // would change nothing. Revisited areas are mostly that.
      const int64_t strip_ty = FloorDiv(cy, kTileCells);
      const int64_t strip_last = std::min(cy_last, strip_first + kStripRows - 1);
      const double y0 = (static_cast<double>(cy) + 0.5) * kCellM;
      const double y1 = (static_cast<double>(strip_last) + 0.5) * kCellM;
      double x_min = 0.0, x_max = 0.0;
      int64_t qx_first = 0, qx_last = -1;
      if (eroded) {
        // The cells whose centre lies in the eroded triangle, a micrometre
        // grown (rounding).
        if (!BandRange(corners[0], corners[1], corners[2], y0 - 1e-6, y1 + 1e-6, &x_min, &x_max)) {
          cy = strip_last;  // the triangle misses these rows
          continue;
        }
        qx_first = CeilInt((std::max(x_min, x_lo) - 1e-6) / kCellM - 0.5);
        qx_last = FloorInt((std::min(x_max, x_hi) + 1e-6) / kCellM - 0.5);
      } else if (BandRange(origin, a, b, y0, y1, &x_min, &x_max)) {
        // The view's whole triangle holds the region, a cell wider.
        qx_first = CellIndex(std::max(x_min, x_lo)) - 1;
        qx_last = CellIndex(std::min(x_max, x_hi)) + 1;
      }
      if (qx_first <= qx_last &&
          Quiet(strip_ty, static_cast<size_t>(cy - strip_ty * kTileCells),
                static_cast<size_t>(strip_last - strip_ty * kTileCells), qx_first, qx_last)) {
        cy = strip_last;
        continue;
      }
    }
    const double y = (static_cast<double>(cy) + 0.5) * kCellM;
    double lo = x_lo, hi = x_hi;
    for (const HalfPlane& h : planes) {
      const double rhs = h.c - h.n.y() * y;  // n.x * x >= rhs
      if (std::abs(h.n.x()) < 1e-12) {
        if (rhs > 0.0) hi = lo - 1.0;  // the row lies outside this edge
      } else if (h.n.x() > 0.0) {
        lo = std::max(lo, rhs / h.n.x());
      } else {
        hi = std::min(hi, rhs / h.n.x());
      }
    }
    if (hi < lo) continue;
    // Cells whose centre (cx + 0.5) * kCellM lies in [lo, hi].
    const int64_t cx_first = CeilInt(lo / kCellM - 0.5);
    const int64_t cx_last = FloorInt(hi / kCellM - 0.5);
    if (cx_first > cx_last) continue;
    const int64_t ty = FloorDiv(cy, kTileCells);
    if (!has_row || ty != row_ty) {
      row_tiles_.assign(static_cast<size_t>(tx_count), nullptr);
      row_ty = ty;
      has_row = true;
    }
    const size_t row = static_cast<size_t>(cy - ty * kTileCells);
    for (int64_t cx = cx_first; cx <= cx_last;) {
      // One run of cells per tile: a mask of the run's columns in the row.
      const int64_t tx = FloorDiv(cx, kTileCells);
      const int64_t run_end = std::min(cx_last, (tx + 1) * kTileCells - 1);
      const int first = static_cast<int>(cx - tx * kTileCells);
      const int last = static_cast<int>(run_end - tx * kTileCells);
      cx = run_end + 1;
      TileData* tile = nullptr;
      const int64_t column = tx - tx_base;
      if (column >= 0 && column < tx_count) {
        TileData*& cached = row_tiles_[static_cast<size_t>(column)];
        if (cached == nullptr) cached = &TileAt(tx, ty);
        tile = cached;
      } else {
        tile = &TileAt(tx, ty);
      }
      const uint32_t run =
          (last == kTileCells - 1 ? ~0u : (1u << (last + 1)) - 1u) & ~((1u << first) - 1u);
      for (uint32_t seen = run & tile->watched[row]; seen != 0; seen &= seen - 1u) {
        watched_passes_.push_back(TileKey(tx * kTileCells + __builtin_ctz(seen), cy));
      }
      // Saturated counts stay as they are: still a function of the triangle set.
      uint32_t todo = run & ~tile->saturated[row];
      while (todo != 0) {
        const int bit = __builtin_ctz(todo);
        todo &= todo - 1u;
        uint8_t& count = tile->counts[row * kTileCells + static_cast<size_t>(bit)];
        if (++count == min_count_) {
          newly_free_.push_back(TileKey(tx * kTileCells + bit, cy));
          tile->saturated[row] |= 1u << bit;
        }
      }
    }
  }
}

void FreeSpaceGrid::AddLine(const Segment2& line) {
  const int steps = std::max(1, static_cast<int>(std::ceil(line.length() / (0.25 * kCellM))));
  std::vector<uint64_t> cells;
  cells.reserve(static_cast<size_t>(steps) + 1);
  for (int i = 0; i <= steps; ++i) {
    const Vec2 p = line.a + (static_cast<double>(i) / steps) * (line.b - line.a);
    cells.push_back(TileKey(CellIndex(p.x()), CellIndex(p.y())));
  }
  std::sort(cells.begin(), cells.end());
  cells.erase(std::unique(cells.begin(), cells.end()), cells.end());
  for (uint64_t cell : cells) {
    const Vec2 centre = CellCentre(cell);
    const int64_t cx = CellIndex(centre.x()), cy = CellIndex(centre.y());
    const int64_t tx = FloorDiv(cx, kTileCells), ty = FloorDiv(cy, kTileCells);
    TileData& tile = TileAt(tx, ty);
    const size_t row = static_cast<size_t>(cy - ty * kTileCells);
    const int bit = static_cast<int>(cx - tx * kTileCells);
    uint8_t& count = tile.counts[row * kTileCells + static_cast<size_t>(bit)];
    if (count >= min_count_) continue;
    if (++count == min_count_) {
      newly_free_.push_back(cell);
      tile.saturated[row] |= 1u << bit;
    }
  }
}

void FreeSpaceGrid::Watch(uint64_t cell_key, bool on) {
  const auto cx = static_cast<int64_t>(static_cast<int32_t>(static_cast<uint32_t>(cell_key >> 32)));
  const auto cy =
      static_cast<int64_t>(static_cast<int32_t>(static_cast<uint32_t>(cell_key & 0xffffffffu)));
  const int64_t tx = FloorDiv(cx, kTileCells), ty = FloorDiv(cy, kTileCells);
  const uint32_t bit = 1u << static_cast<int>(cx - tx * kTileCells);
  uint32_t& mask = TileAt(tx, ty).watched[static_cast<size_t>(cy - ty * kTileCells)];
  mask = on ? (mask | bit) : (mask & ~bit);
}

std::vector<uint64_t> FreeSpaceGrid::TakeWatchedPasses() {
  std::vector<uint64_t> out;
  out.swap(watched_passes_);
  return out;
}

std::vector<uint64_t> FreeSpaceGrid::TakeNewlyFree() {
  std::vector<uint64_t> out;
  out.swap(newly_free_);
  std::sort(out.begin(), out.end());
  return out;
}

uint64_t FreeSpaceGrid::CellKeyOf(const Vec2& p) {
  return TileKey(CellIndex(p.x()), CellIndex(p.y()));
}

Vec2 FreeSpaceGrid::CellCentre(uint64_t cell_key) {
  const auto cx = static_cast<int32_t>(static_cast<uint32_t>(cell_key >> 32));
  const auto cy = static_cast<int32_t>(static_cast<uint32_t>(cell_key & 0xffffffffu));
  return Vec2((cx + 0.5) * kCellM, (cy + 0.5) * kCellM);
}

std::vector<std::pair<uint64_t, const FreeSpaceGrid::Tile*>> FreeSpaceGrid::SortedTiles() const {
  std::vector<std::pair<uint64_t, const Tile*>> out;
  out.reserve(tiles_.size());
  tiles_.ForEach([&out](uint64_t key, const TileData& tile) {
    // A tile that only Watch created (no count yet).
    if (std::all_of(tile.counts.begin(), tile.counts.end(), [](uint8_t c) { return c == 0; })) {
      return;
    }
    out.emplace_back(key, &tile.counts);
  });
  std::sort(out.begin(), out.end(), [](const auto& x, const auto& y) { return x.first < y.first; });
  return out;
}

void FreeSpaceGrid::RestoreTile(uint64_t key, const Tile& tile) {
  TileData& data = tiles_.FindOrAdd(key);
  data.counts = tile;
  for (size_t i = 0; i < tile.size(); ++i) {
    if (tile[i] < min_count_) continue;
    // Snapshots written before counts stopped at min_count hold up to 255:
    // stopped here too, so the next snapshot has a fresh engine's bytes.
    data.counts[i] = static_cast<uint8_t>(min_count_);
    data.saturated[i / kTileCells] |= 1u << (i % kTileCells);
  }
}

}  // namespace mapd::fusion
