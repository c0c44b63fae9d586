// Free-space evidence for wall consolidation (docs/algorithms.md A.11).
//
// Line features say where surfaces are, not where the sensor saw through:
// a 5 m stretch of a wall line with no feature on it is either occluded (a
// fence or another building stood in front) or open (a passage between two
// buildings). Every observation has a sensor pose, though, and the rays that
// reached an observed segment crossed the triangle (sensor origin, a, b)
// unobstructed. FreeSpaceGrid counts, per cell of a sparse grid, how many
// such visibility triangles covered it; a cell with at least min_count is
// "observed free".
//
// A triangle marks a cell only if the cell's centre lies inside both rays by
// at least kSideErosionPerM times its distance from the origin along the ray
// (a ray grazing a building corner, misplaced by angular pose noise, must not
// mark the corner's wall; the misplacement grows with range, and near the
// sensor, where the robot itself stood, there is none to fear) and at least
// kSegmentMarginM in front of the observed segment (a wall's own
// observations, noisy along their normal, never mark its line). A constant
// 0.3 m side erosion (before issue 40) erased the whole apex of every narrow
// triangle, so crossings the robot drove through and doorways it looked
// through stayed "unseen" and consolidation bridged them (docs/algorithms.md
// A.11 has the measurements). Cells are kCellM square, in tiles of
// kTileCells x kTileCells created on first touch. Counts stop at min_count:
// nothing reads a count beyond whether it reached min_count, and a cell that
// did is skipped by every later triangle (one mask test per row of a tile),
// so a revisited area costs a triangle's rows, not its cells. Counts, and
// which cells are free, are a function of the set of triangles added,
// whatever their order. (Until issue 40's cost work counts ran on to 255 and
// every view of a revisited area incremented each cell it covered: 14 % of a
// city soak's fusion time. Snapshots written then still load: a count of at
// least min_count is free either way.)
#ifndef MAPD_FUSION_FREE_SPACE_H_
#define MAPD_FUSION_FREE_SPACE_H_

#include <array>
#include <cmath>
#include <cstdint>
#include <memory>
#include <vector>

#include "fusion/floor_int.h"
#include "geometry/segment2.h"

namespace mapd::fusion {

class FreeSpaceGrid {
 public:
  static constexpr double kCellM = 0.25;
  static constexpr double kSideErosionPerM = 0.005;  // metres per metre of range (0.3 deg)
  static constexpr double kSegmentMarginM = 0.4;
  static constexpr int kTileCells = 32;
  using Tile = std::array<uint8_t, kTileCells * kTileCells>;

  // REQUIRES: 1 <= min_count <= 255, range_m > 0.
  FreeSpaceGrid(uint32_t min_count, double range_m) : min_count_(min_count), range_m_(range_m) {}

  // Adds the visibility triangle of `segment`, observed from `origin` (map
  // frame), clipped to the square of half width range_m around `origin`: the
  // cells one view writes are at most (2 range_m / kCellM)^2, however far
  // and long the segment (FusionParams::evidence_range_m).
  void AddView(const geometry::Vec2& origin, const geometry::Segment2& segment);

  // Counts one in every cell the segment crosses (sampled every kCellM / 4,
  // each cell once): proofs of occlusion (occlusion_proof.h) use a grid of
  // their own this way.
  void AddLine(const geometry::Segment2& line);

  // Whether the cell that contains p is observed free.
  bool IsFree(const geometry::Vec2& p) const { return Probe(*this).IsFree(p); }

  // IsFree for many nearby points (samples along a line): keeps the last tile.
  class Probe {
   public:
    explicit Probe(const FreeSpaceGrid& grid) : grid_(grid) {}
    // Inline: callers probe every half cell along lines (piercing, gaps).
    bool IsFree(const geometry::Vec2& p) {
      const int64_t cx = FloorInt(p.x() / kCellM);
      const int64_t cy = FloorInt(p.y() / kCellM);
      const int64_t tx = cx >> kTileShift, ty = cy >> kTileShift;  // floor division
      const uint64_t key = TileKey(tx, ty);
      if (!has_tile_ || key != tile_key_) {
        const TileData* found = grid_.tiles_.Find(key);
        tile_ = found == nullptr ? nullptr : &found->counts;
        tile_key_ = key;
        has_tile_ = true;
      }
      if (tile_ == nullptr) return false;
      const auto row = static_cast<size_t>(cy & (kTileCells - 1));
      const auto column = static_cast<size_t>(cx & (kTileCells - 1));
      return (*tile_)[row * kTileCells + column] >= grid_.min_count_;
    }

   private:
    const FreeSpaceGrid& grid_;
    bool has_tile_ = false;
    uint64_t tile_key_ = 0;
    const Tile* tile_ = nullptr;  // null: no tile there
  };

  // The cells (CellKeyOf) that became free (reached min_count) since the last
  // call, ascending; clears the list.
  std::vector<uint64_t> TakeNewlyFree();
  static uint64_t CellKeyOf(const geometry::Vec2& p);
  static geometry::Vec2 CellCentre(uint64_t cell_key);

  // Watched cells (retirement, wall_retirement.h): AddView reports every
  // watched cell a triangle covers, saturated or not, until taken. Watching
  // creates the cell's tile (its counts stay zero; SortedTiles leaves tiles
  // with no count out, so snapshots do not depend on what was watched).
  void Watch(uint64_t cell_key, bool on);
  // The watched cells covered since the last call, in the order covered
  // (a cell once per triangle that covered it); clears the list.
  std::vector<uint64_t> TakeWatchedPasses();

  // Test hook: AddView visiting every row, without skipping strips it would
  // not change or that the triangle misses (the reference its skipping must
  // equal).
  void set_skip_quiet_rows(bool on) { skip_quiet_rows_ = on; }

  size_t tile_count() const { return tiles_.size(); }
  size_t memory_bytes() const { return tiles_.size() * (sizeof(TileData) + 48); }

  // Snapshots: tiles by key, and restoring one (REQUIRES: key not present).
  // A restored grid has no newly free cells.
  std::vector<std::pair<uint64_t, const Tile*>> SortedTiles() const;
  void RestoreTile(uint64_t key, const Tile& tile);

 private:
  // A tile's counts and, per row, one bit per cell whose count reached
  // min_count (saturated: it never changes again, and AddView skips it).
  // Derived from the counts (not in snapshots).
  struct TileData {
    Tile counts{};
    std::array<uint32_t, kTileCells> saturated{};
    std::array<uint32_t, kTileCells> watched{};  // see Watch
  };
  static_assert(kTileCells == 32, "one uint32_t mask per tile row");

  // Tile key -> tile, by open addressing (linear probing, a power-of-two
  // table at most half full; tiles are never erased). AddView looks tiles up
  // for every strip of rows it tests: std::unordered_map's identity hash
  // took a division per bucket and per chained node, half of that test's
  // time in a city soak; this a multiply and, mostly, one slot.
  class TileTable {
   public:
    size_t size() const { return size_; }
    const TileData* Find(uint64_t key) const {
      if (size_ == 0) return nullptr;
      for (size_t i = Home(key);; i = (i + 1) & mask_) {
        if (slots_[i].tile == nullptr) return nullptr;
        if (slots_[i].key == key) return slots_[i].tile;
      }
    }
    // The tile at key, created (zero) if absent.
    TileData& FindOrAdd(uint64_t key);
    // fn(key, tile) for every tile, in no particular order.
    template <typename Fn>
    void ForEach(Fn&& fn) const {
      for (const Slot& slot : slots_) {
        if (slot.tile != nullptr) fn(slot.key, *slot.tile);
      }
    }

   private:
    struct Slot {
      uint64_t key = 0;
      TileData* tile = nullptr;  // null: empty
    };
    size_t Home(uint64_t key) const {
      uint64_t h = key * 0x9E3779B97F4A7C15ULL;
      h ^= h >> 32;
      return static_cast<size_t>(h) & mask_;
    }
    void Grow();

    std::vector<Slot> slots_;
    size_t mask_ = 0;
    size_t size_ = 0;
    std::vector<std::unique_ptr<TileData>> storage_;
  };
  static constexpr int kTileShift = 5;  // kTileCells == 1 << kTileShift

  static uint64_t TileKey(int64_t tx, int64_t ty) {
    return (static_cast<uint64_t>(static_cast<uint32_t>(tx)) << 32) |
           static_cast<uint64_t>(static_cast<uint32_t>(ty));
  }
  TileData& TileAt(int64_t tx, int64_t ty);
  // Whether cells [cx_first, cx_last] of rows [row_first, row_last] of tile
  // row ty are all saturated and unwatched (AddView would change nothing).
  bool Quiet(int64_t ty, size_t row_first, size_t row_last, int64_t cx_first,
             int64_t cx_last) const;

  const uint32_t min_count_;
  const double range_m_;
  bool skip_quiet_rows_ = true;
  TileTable tiles_;
  // AddView's scratch: the tiles of the tile row it is in, by column.
  std::vector<TileData*> row_tiles_;
  std::vector<uint64_t> newly_free_;      // cell keys (TileKey packing of cell indices)
  std::vector<uint64_t> watched_passes_;  // cell keys, see TakeWatchedPasses
};

}  // namespace mapd::fusion

#endif  // MAPD_FUSION_FREE_SPACE_H_
