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

}  // namespace

FreeSpaceGrid::TileData& FreeSpaceGrid::TileAt(int64_t tx, int64_t ty) {
  std::unique_ptr<TileData>& tile = tiles_[TileKey(tx, ty)];
  if (!tile) tile = std::make_unique<TileData>();
  return *tile;
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
  for (int64_t cy = cy_first; cy <= cy_last; ++cy) {
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
  for (const auto& [key, tile] : tiles_) {
    // A tile that only Watch created (no count yet).
    if (std::all_of(tile->counts.begin(), tile->counts.end(), [](uint8_t c) { return c == 0; })) {
      continue;
    }
    out.emplace_back(key, &tile->counts);
  }
  std::sort(out.begin(), out.end(), [](const auto& x, const auto& y) { return x.first < y.first; });
  return out;
}

void FreeSpaceGrid::RestoreTile(uint64_t key, const Tile& tile) {
  auto data = std::make_unique<TileData>();
  data->counts = tile;
  for (size_t i = 0; i < tile.size(); ++i) {
    if (tile[i] < min_count_) continue;
    // Snapshots written before counts stopped at min_count hold up to 255:
    // stopped here too, so the next snapshot has a fresh engine's bytes.
    data->counts[i] = static_cast<uint8_t>(min_count_);
    data->saturated[i / kTileCells] |= 1u << (i % kTileCells);
  }
  tiles_[key] = std::move(data);
}

}  // namespace mapd::fusion
