// The candidates of WallConsolidator's neighbour search, cached per piece.
//
// A piece's neighbours are looked for among the pieces filed (wall
// consolidation files each piece at points along its fitted segment, every
// kPieceStepM at most) in the index cells of up to three bands around the
// piece's segment: its own band and, with evidence, one beyond each end for
// occluded gaps. A piece is refitted, and its neighbours recomputed, on
// almost every feature it takes, while the refit moves it by millimetres:
// probing the bands' cells every time was 12-15 % of the fuser's CPU in the
// city workload (docs/long-running.md, "Where the fuser's time goes").
//
// The cache searches each piece's bands widened by kMarginM once. While the
// piece's bands stay within kMarginM of the ones searched (every band end
// within kMarginM of its end then), the widened search covers the cells the
// exact bands meet, so the pieces filed in them were either found then or
// filed since; pieces filed since are read from a log of filings. The
// candidates are a superset: the caller keeps those whose filed cells meet
// the exact bands (FiledInBands), the same set a fresh search finds.
#ifndef MAPD_FUSION_WALL_CANDIDATES_H_
#define MAPD_FUSION_WALL_CANDIDATES_H_

#include <cstdint>
#include <functional>
#include <unordered_map>
#include <vector>

#include "fusion/cluster_stats.h"
#include "fusion/grid_index.h"
#include "geometry/segment2.h"

namespace mapd::fusion {

// Pieces are filed in the index at points at most this far apart along their
// fitted segment (and the index's cells are this wide): every point of a
// piece is then within half of it from a filed point.
inline constexpr double kPieceStepM = 2.0;

// The filed points of segment s: FiledPoint(s, i, FilingSteps(s)) for i in
// [0, FilingSteps(s)], both ends included.
int FilingSteps(const geometry::Segment2& s);
inline geometry::Vec2 FiledPoint(const geometry::Segment2& s, int i, int steps) {
  return s.a + (static_cast<double>(i) / steps) * (s.b - s.a);
}

using PieceIndex = UniformGrid<ClusterId>;

// One band of a neighbour search: the cells within radius_m of segment.
struct SearchBand {
  geometry::Segment2 segment;
  double radius_m = 0.0;
};

// Whether a search of `bands` finds a piece filed along `filed`: one of its
// filed points lies in a cell one of the bands meets.
bool FiledInBands(const PieceIndex& index, const geometry::Segment2& filed,
                  const std::vector<PieceIndex::SegmentBand>& bands);

class WallCandidates {
 public:
  static constexpr double kMarginM = 1.0;

  // filed_segment(id): the segment a piece is filed along in `index`, or
  // null if it is not filed (gone, or retired).
  WallCandidates(const PieceIndex* index,
                 std::function<const geometry::Segment2*(ClusterId)> filed_segment)
      : index_(index), filed_segment_(std::move(filed_segment)) {}

  // A piece was filed in the index, new or in other cells than before.
  void Filed(ClusterId id);
  // A piece left: its cached search goes.
  void Forget(ClusterId id) { cache_.erase(id); }
  // Every cached search is dropped (the bands' shape changed: evidence).
  void Clear();

  // A superset of the pieces a search of `bands` finds in the index,
  // ascending, without duplicates; it may hold `id` itself, and pieces no
  // longer filed.
  const std::vector<ClusterId>& Candidates(ClusterId id, const std::vector<SearchBand>& bands);

 private:
  struct Entry {
    std::vector<SearchBand> searched;  // the bands searched, unwidened
    std::vector<PieceIndex::SegmentBand> widened;
    uint64_t seen = 0;  // filings_ read up to this sequence number
    std::vector<ClusterId> ids;
  };
  // Whether every band is within kMarginM of the one searched.
  static bool Covers(const Entry& entry, const std::vector<SearchBand>& bands);
  void Search(const std::vector<SearchBand>& bands, Entry* entry) const;

  const PieceIndex* index_;
  std::function<const geometry::Segment2*(ClusterId)> filed_segment_;
  std::unordered_map<ClusterId, Entry> cache_;
  // Pieces filed, in order: filings_[k] has sequence number first_seq_ + k.
  // The older half is dropped when it grows long; entries that had not read
  // it search again.
  std::vector<ClusterId> filings_;
  uint64_t first_seq_ = 0;
};

}  // namespace mapd::fusion

#endif  // MAPD_FUSION_WALL_CANDIDATES_H_
