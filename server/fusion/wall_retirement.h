// Retirement of walls the robots see through (docs/algorithms.md A.12).
//
// Buildings change: a partition is taken down, shelves are moved, a door is
// opened for good. The fusion keeps every cluster it ever published, so
// without this a wall that is gone stays in the map for ever. A wall that is
// gone is seen through: later observations' visibility triangles (free_space.h)
// cover the cells along it, which a standing wall would have blocked. A wall
// merely hidden behind something else is not seen through (the rays stop in
// front of the occluder), so it stays, however long nobody sees it.
//
// The ledger watches, for every published piece (a cluster, before wall
// consolidation), the free-space cells its fitted segment crosses, 0.5 m (at
// most a quarter of its length) trimmed at each end: the fitted end of a wall
// may overshoot its corner, and rays graze corners. Per cell it counts the
// observations whose triangles covered the cell since the piece was last
// supported (a feature joined it); a cell with `views` of them is seen
// through. A support starts the piece's count again. The consolidator
// retires a whole wall (all its pieces) once at least the retire fraction of
// its pieces' cells are seen through: a short fragment at a corner, tilted a
// few degrees off its wall, pokes out into space the robots do see, and alone
// it would come and go on a building that never changed. Counts saturate at
// 255, so what the ledger holds is a function of the pieces and the
// observations since their last support: deterministic, in snapshots, and
// bounded by the length of the published walls, not by history.
#ifndef MAPD_FUSION_WALL_RETIREMENT_H_
#define MAPD_FUSION_WALL_RETIREMENT_H_

#include <cstdint>
#include <map>
#include <string>
#include <unordered_map>
#include <vector>

#include "fusion/free_space.h"
#include "geometry/segment2.h"

namespace mapd::fusion {

using ClusterId = uint64_t;

class RetirementLedger {
 public:
  // REQUIRES: 1 <= views <= 255; `grid` outlives the ledger and is the grid
  // whose views are passed to AddPasses.
  RetirementLedger(uint32_t views, FreeSpaceGrid* grid) : views_(views), grid_(grid) {}

  // Watches `piece` along `fitted`. A piece watched already keeps its cells
  // while its segment stays within a quarter cell of the one they were taken
  // from (a refit moves a wall by millimetres on most supports), and keeps
  // its counts unless `supported`; new cells start at zero.
  void Watch(ClusterId piece, const geometry::Segment2& fitted, bool supported);
  void Unwatch(ClusterId piece);
  bool Watches(ClusterId piece) const { return entries_.count(piece) != 0; }

  // The watched cells one observation's views covered
  // (FreeSpaceGrid::TakeWatchedPasses after all of them): each cell counts
  // once. Appends the pieces that have more cells seen through now to
  // `changed`, ascending.
  void AddPasses(std::vector<uint64_t> cells, std::vector<ClusterId>* changed);
  // A watched piece's cells, and how many of them are seen through (0, 0 if
  // not watched).
  std::pair<size_t, size_t> SeenThrough(ClusterId piece) const;

  // Snapshots: per watched piece, ascending, the segment its cells were taken
  // from and its counts (one byte a cell); Restore replaces a piece's entry
  // and returns false if the counts do not fit the segment's cells.
  struct Entry {
    geometry::Segment2 segment;
    std::vector<uint64_t> cells;  // FreeSpaceGrid cell keys, ascending
    std::string passes;           // per cell, as unsigned bytes
    uint32_t seen_cells = 0;      // cells with passes >= views
  };
  const std::map<ClusterId, Entry>& entries() const { return entries_; }
  bool Restore(ClusterId piece, const geometry::Segment2& segment, const std::string& passes);

  // The cells of `fitted` that a ledger watches (see above).
  static std::vector<uint64_t> CellsOf(const geometry::Segment2& fitted);

 private:
  void Attach(ClusterId piece, Entry* entry);
  void Detach(ClusterId piece, const Entry& entry);

  const uint32_t views_;
  FreeSpaceGrid* const grid_;
  std::map<ClusterId, Entry> entries_;
  // Cell -> (piece, index of the cell in the piece's entry).
  std::unordered_map<uint64_t, std::vector<std::pair<ClusterId, uint32_t>>> watchers_;
};

}  // namespace mapd::fusion

#endif  // MAPD_FUSION_WALL_RETIREMENT_H_
