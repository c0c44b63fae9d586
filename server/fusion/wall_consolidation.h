// Wall consolidation, beyond the paper (docs/algorithms.md, section A.11).
//
// The three criteria link two features only when each one's centre lies within
// eta of the other AND their feature circles overlap: two pieces of one wall
// seen from its two ends (a long wall is rarely seen whole from one pose) can
// fail criterion 3 although they lie on the same line, so the paper publishes
// one wall as several overlapping features. The consolidator takes the
// engine's published clusters ("pieces") and publishes as one feature
// ("wall") every set of pieces connected by OnOneWall:
//
//   L = the longer of p, q (ties: the smaller id), S = the other;
//   OnOneWall(p, q) iff
//     a. the included angle of their fitted directions is <= delta_rad, and
//        both endpoints of S lie within wall_offset_m of L's fitted line, and S's
//        extent along L overlaps L's or leaves a gap of <= wall_gap_m; or
//     b. each endpoint of one lies within wall_offset_m of an endpoint of the other
//        (near-identical features: corner snapping would make them one
//        segment, whatever their directions); or
//     c. both endpoints of S lie within wall_offset_m of L's line and S's extent
//        lies within L's (a short piece wholly inside L's band, e.g. a
//        fragment at a corner, whose direction is poorly determined).
//
// A wall is a connected component of that relation over the pieces, passed
// through the chain guard (chain_guard.h) with the pieces as its members when
// the guard is on, so consolidation never rebuilds a chain the guard cut. Its
// statistics are the pieces' merged in ascending id order; its id is the
// smallest piece id. Walls are thus a function of the piece set alone:
// deterministic and independent of arrival order, like the pieces themselves.
// Off (FusionParams::consolidate false), every piece is its own wall.
//
// With free-space evidence (FusionParams::wall_occluded_gap_m > 0,
// free_space.h), rule a also joins pieces whose gap exceeds wall_gap_m, up to
// wall_occluded_gap_m and wall_occluded_gap_ratio times S's length, if no sample of the gap on L's
// line (every FreeSpaceGrid::kCellM / 2) lies in an observed-free cell; and a piece "pierced" by an
// observed-free cell (a sample of its fitted segment, the last kPierceTrimM at each end aside)
// joins no other piece. Walls are then a function of (pieces, evidence). Cells only ever become
// free, so evidence can only part walls: a wall joined across an occluded gap is re-resolved when a
// cell of that gap becomes free (the consolidator records the cells of the
// gaps it bridged), and a piece near a newly free cell is re-checked for
// piercing.
//
// Bounded (FusionParams::max_wall_pieces, bounded mode): a component of more
// than max_wall_pieces pieces is not consolidated; each of its pieces is a wall
// of its own. Still a function of the piece set (and evidence); the point is
// that Resolve() then stops walking a component after max_wall_pieces pieces.
//
// Retirement (FusionParams::retire_views > 0, with the evidence;
// wall_retirement.h): a wall the robots saw through since its pieces' last
// supports leaves the published map with all its pieces (they are kept,
// unpublished, and HasPiece() still names them); an Upsert that adds members
// or support to a piece brings that piece back.
//
// Incremental: the engine reports pieces that appeared, changed or vanished;
// Resolve() recomputes only the walls those pieces belonged to or now reach.
// A piece of an oversized component that changes or vanishes also touches
// its former neighbours (what is left of the component may now be small).
#ifndef MAPD_FUSION_WALL_CONSOLIDATION_H_
#define MAPD_FUSION_WALL_CONSOLIDATION_H_

#include <map>
#include <memory>
#include <optional>
#include <unordered_map>
#include <vector>

#include "fusion/cluster_stats.h"
#include "fusion/free_space.h"
#include "fusion/grid_index.h"
#include "fusion/params.h"
#include "fusion/piercing.h"
#include "fusion/wall_candidates.h"
#include "fusion/wall_retirement.h"

namespace mapd::fusion {

// Rule b: each endpoint of one lies within offset_m of an endpoint of the other.
bool NearIdentical(const geometry::Segment2& p, const geometry::Segment2& q, double offset_m);

// The relation above on two fitted segments named by their cluster ids.
// `free_space` (null: no evidence) enables the occluded-gap join; when it
// joins across such a gap, the gap's samples on L's line are appended to
// `gap_samples` if not null.
// `proof` (cells an observation proved occluded, occlusion_proof.h; null:
// none) must cover a gap of up to params.wall_proof_gap_m for it to join.
bool OnOneWall(const geometry::Segment2& p, ClusterId p_id, const geometry::Segment2& q,
               ClusterId q_id, const FusionParams& params,
               const FreeSpaceGrid* free_space = nullptr,
               std::vector<geometry::Vec2>* gap_samples = nullptr,
               const FreeSpaceGrid* proof = nullptr);

class WallConsolidator {
 public:
  // support_cap: as ClusterStats::Merge (the engine's).
  WallConsolidator(const FusionParams& params, uint32_t support_cap);
  // Neither copied nor moved: the candidate cache reads pieces_ through a
  // pointer to this object.
  WallConsolidator(const WallConsolidator&) = delete;
  WallConsolidator& operator=(const WallConsolidator&) = delete;

  // Piece stats.id appeared or changed. Returns false (and records nothing)
  // if it is unchanged: same member count, support and fitted segment.
  bool Upsert(const ClusterStats& stats, const ClusterStats::Fit& fit);
  // Settled walls (FusionParams::refit_tolerance_m): if piece stats.id is
  // published (not retired) and `fit` moves neither endpoint of the fit it
  // was last upserted with by more than tolerance_m, and stats adds no robot
  // to it, records the sighting (retirement) and returns true: the piece
  // keeps the statistics and fit it was last upserted with, so its wall is a
  // function of what was upserted, as a restored snapshot has it. Else
  // returns false and changes nothing (the caller then upserts).
  bool Settle(const ClusterStats& stats, const ClusterStats::Fit& fit, double tolerance_m);
  void Erase(ClusterId piece);
  // The wall a published piece is on, and a wall's pieces (ascending), as of
  // the last Resolve(). REQUIRES: the piece is published / the wall exists.
  ClusterId WallOf(ClusterId piece) const { return pieces_.at(piece).wall; }
  bool OnAWall(ClusterId piece) const {
    auto it = pieces_.find(piece);
    return it != pieces_.end() && it->second.has_wall;
  }
  const std::vector<ClusterId>& WallPieces(ClusterId wall) const { return walls_.at(wall).pieces; }
  bool HasPiece(ClusterId piece) const { return pieces_.count(piece) != 0; }
  // Free-space evidence: the visibility triangle of `segment` seen from
  // `origin`. A no-op unless wall_occluded_gap_m > 0. The grid exists from the
  // first view on: a consolidator never given one (observations without a
  // sensor origin) has no evidence and joins no occluded gap, as before.
  void AddView(const geometry::Vec2& origin, const geometry::Segment2& segment) {
    if (EnableFreeSpace() != nullptr) free_space_->AddView(origin, segment);
  }
  // Free-space evidence and proofs of occlusion from one observation: the
  // visibility triangle of each segment (AddView) and the stretches its
  // segments prove occluded (occlusion_proof.h; with wall_proof_gap_m > 0).
  void AddObservation(const geometry::Vec2& origin,
                      const std::vector<geometry::Segment2>& segments);
  // Creates the (empty) grids if wall_occluded_gap_m > 0 and returns the
  // free-space one, else null. Snapshots restore the grids through it.
  FreeSpaceGrid* EnableFreeSpace();
  // Null before the first view, or with wall_occluded_gap_m = 0.
  const FreeSpaceGrid* free_space() const { return free_space_.get(); }
  // The proofs of occlusion: a cell counts once proven. Null as free_space(),
  // and with wall_proof_gap_m = 0.
  const FreeSpaceGrid* proof() const { return proof_.get(); }
  FreeSpaceGrid* mutable_proof() { return proof_.get(); }
  // All pieces, retired ones included, ascending id (snapshots).
  const std::map<ClusterId, ClusterStats>& pieces() const { return piece_stats_; }
  // Retirement: pieces retired now, ascending; the ledger (null without
  // retirement or before the first view); and, for snapshots, retiring a
  // restored piece again (REQUIRES: HasPiece(piece)).
  std::vector<ClusterId> RetiredPieces() const;
  size_t retired_count() const { return retired_count_; }
  const RetirementLedger* ledger() const { return ledger_.get(); }
  RetirementLedger* mutable_ledger() { return ledger_.get(); }
  void Retire(ClusterId piece);

  struct Wall {
    // The wall's statistics; stats().id names the wall. A one-piece wall's
    // are its piece's own, by reference: valid until the consolidator next
    // changes (most walls are one piece, and copying their statistics was a
    // tenth of the fuser's allocations).
    const ClusterStats& stats() const { return merged ? *merged : *single; }
    std::optional<ClusterStats> merged;  // two pieces or more
    const ClusterStats* single = nullptr;
    ClusterStats::Fit fit;
    std::vector<ClusterId> pieces;  // ascending; pieces.front() == stats().id
  };
  // Recomputes the walls touched since the last call. `removed`: walls that
  // existed and exist no more; `walls`: every wall that contains a touched
  // piece, changed or not (the caller compares).
  void Resolve(std::vector<ClusterId>* removed, std::vector<Wall>* walls);

  // Test hook: while on, every cached neighbour list Resolve() reads is
  // compared with a fresh search, and every touched piece's piercing with a
  // fresh check; mismatches are counted (process-wide).
  static void SetVerifyNeighbourCache(bool on);
  static size_t neighbour_cache_mismatches();
  static size_t piercing_mismatches();

 private:
  struct Piece {
    ClusterStats::Fit fit;
    ClusterId wall = 0;
    bool has_wall = false;
    bool pierced = false;  // an observed-free cell on its fitted segment: joins nothing
    // Not pierced: how far its samples may still move before a fresh check
    // (piercing.h), metres; 0 until checked with evidence.
    double pierce_clearance_m = 0.0;
    // Its component had more than max_wall_pieces pieces at the last Resolve()
    // (it is then a wall of its own).
    bool oversized = false;
    // Seen through since its last support (wall_retirement.h): not filed in
    // the index, on no wall.
    bool retired = false;
    // Resolve()'s walk: the number of the last Resolve() that reached it, and
    // that found it in an oversized component (marks, not sets: a set of
    // ids allocated a node per piece reached, every Resolve()).
    uint64_t reached_in = 0;
    uint64_t oversized_in = 0;
  };
  // Counts this observation's passes over watched cells (the ledger) and
  // retires every wall whose pieces are seen through on retire_fraction of
  // their cells.
  void RetireSeenThrough();
  // Sets piece->pierced for its fit, whose samples moved at most shift_m
  // since the last call: without a fresh check while within its clearance.
  void UpdatePiercing(Piece* piece, double shift_m);
  // A piece of an oversized component is about to change or vanish: its
  // current neighbours are resolved again.
  void TouchNeighboursIfOversized(ClusterId id);
  void Index(ClusterId id, const geometry::Segment2& s, bool insert);
  // Pieces on one wall with `id`, ascending, computed from the index (through
  // the candidate cache if cached_search; the test hook checks it against a
  // search of the index). Records the cells of the occluded gaps it bridges
  // (gap_watch_) if record_gaps.
  std::vector<ClusterId> Neighbours(ClusterId id, bool record_gaps = true,
                                    bool cached_search = true);
  // The neighbour cache (neighbours_): recomputes `id`'s list and mirrors the
  // change into its old and new neighbours' lists; drops a piece that left.
  void RefreshNeighbours(ClusterId id);
  void DropNeighbours(ClusterId id);
  // neighbours_.at(id); with the test hook on, checked against Neighbours().
  const std::vector<ClusterId>& CachedNeighbours(ClusterId id);
  // Cells that became free: touches the walls that bridged them and the
  // pieces whose piercing they may change.
  void TakeEvidence();
  // Whether the guard's cut of a component into head | tail (indices into
  // it) would separate two near-identical pieces (rule b).
  bool Twins(const std::vector<ClusterId>& component, const std::vector<uint32_t>& head,
             const std::vector<uint32_t>& tail) const;
  // The walls of one connected component of pieces (ascending ids).
  void WallsOf(const std::vector<ClusterId>& component, std::vector<Wall>* walls) const;

  const FusionParams params_;
  const uint32_t support_cap_;
  const size_t max_wall_pieces_;  // max_wall_pieces in bounded mode, else no limit
  std::map<ClusterId, ClusterStats> piece_stats_;
  std::unordered_map<ClusterId, Piece> pieces_;
  struct WallMembers {
    std::vector<ClusterId> pieces;  // ascending
    uint64_t affected_in = 0;       // the last Resolve() that recomputed the wall
  };
  std::unordered_map<ClusterId, WallMembers> walls_;
  std::vector<ClusterId> touched_pieces_;
  std::vector<ClusterId> touched_walls_;       // walls of pieces that changed or vanished
  PieceIndex index_;                           // pieces filed at points along their fitted segment
  WallCandidates candidates_;                  // of Neighbours(), from index_
  std::unique_ptr<FreeSpaceGrid> free_space_;  // see AddView
  std::unique_ptr<FreeSpaceGrid> proof_;       // see AddObservation
  std::unique_ptr<RetirementLedger> ledger_;   // with free_space_, if retire_views > 0
  size_t retired_count_ = 0;
  // Neighbours() of every piece resolved since it last changed, ascending.
  // Symmetric, as OnOneWall is: q is in p's list iff p is in q's. Resolve()
  // walks components through it, so a wall of k pieces touched by one changed
  // piece costs one index search, not k. What can change OnOneWall(p, q)
  // without touching p or q: nothing (a new free cell on a bridged gap, a new
  // proof near one end and new piercing all touch a piece, see TakeEvidence);
  // touched pieces are recomputed first, their changes mirrored.
  std::unordered_map<ClusterId, std::vector<ClusterId>> neighbours_;
  bool all_neighbours_stale_ = false;  // the evidence appeared: recompute every list
  uint64_t resolve_count_ = 0;         // numbers Resolve()'s walks (Piece::reached_in)
  // Index cells (kPieceStepM) of bridged occluded gaps -> the pieces bridged. Entries of pieces
  // since gone or re-joined otherwise only cause a redundant re-resolve.
  std::unordered_map<uint64_t, std::vector<ClusterId>> gap_watch_;
};

}  // namespace mapd::fusion

#endif  // MAPD_FUSION_WALL_CONSOLIDATION_H_
