#include "fusion/wall_consolidation.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>

#include "fusion/chain_guard.h"
#include "fusion/occlusion_proof.h"
#include "fusion/piercing.h"

namespace mapd::fusion {

using geometry::Cross;
using geometry::Segment2;
using geometry::Vec2;

namespace {

constexpr double kSlackM = 1e-6;

std::atomic<bool> verify_neighbour_cache{false};
std::atomic<size_t> neighbour_cache_mismatch_count{0};
std::atomic<size_t> piercing_mismatch_count{0};

// Inserts x into the ascending ids if absent; erases it if present.
void InsertSorted(std::vector<ClusterId>* ids, ClusterId x) {
  auto it = std::lower_bound(ids->begin(), ids->end(), x);
  if (it == ids->end() || *it != x) ids->insert(it, x);
}
void EraseSorted(std::vector<ClusterId>* ids, ClusterId x) {
  auto it = std::lower_bound(ids->begin(), ids->end(), x);
  if (it != ids->end() && *it == x) ids->erase(it);
}

// The index cell (kPieceStepM square) that contains p, packed as a
// free-space cell key of its indices.
uint64_t IndexCellKey(const Vec2& p) {
  return FreeSpaceGrid::CellKeyOf(Vec2(static_cast<double>(FloorInt(p.x() / kPieceStepM)),
                                       static_cast<double>(FloorInt(p.y() / kPieceStepM))) *
                                  FreeSpaceGrid::kCellM);
}

// Points every kSampleStepM from p + t0 u to p + t1 u (both included).
template <typename Fn>
bool AnySample(const Vec2& p, const Vec2& u, double t0, double t1, Fn&& fn) {
  const int steps = SampleSteps(t0, t1);
  for (int i = 0; i <= steps; ++i) {
    if (fn(SampleAt(p, u, t0, t1, i, steps))) return true;
  }
  return false;
}

std::vector<Vec2> FiledPoints(const Segment2& s) {
  const int steps = FilingSteps(s);
  std::vector<Vec2> points;
  points.reserve(steps + 1);
  for (int i = 0; i <= steps; ++i) points.push_back(FiledPoint(s, i, steps));
  return points;
}

// Whether s and t are filed in the same index cells, point by point. A
// piece's refit moves it by millimetres on most updates: then its index
// entries stay as they are (readers of the index sort what they find, so the
// order of entries within a cell does not matter).
bool SameFiledCells(const UniformGrid<ClusterId>& index, const Segment2& s, const Segment2& t) {
  const int steps = FilingSteps(s);
  if (FilingSteps(t) != steps) return false;
  for (int i = 0; i <= steps; ++i) {
    if (!(index.KeyOf(FiledPoint(s, i, steps)) == index.KeyOf(FiledPoint(t, i, steps)))) {
      return false;
    }
  }
  return true;
}

}  // namespace

bool NearIdentical(const Segment2& p, const Segment2& q, double offset_m) {
  const double d2 = offset_m * offset_m;
  const bool same = (p.a - q.a).squaredNorm() <= d2 && (p.b - q.b).squaredNorm() <= d2;
  const bool swapped = (p.a - q.b).squaredNorm() <= d2 && (p.b - q.a).squaredNorm() <= d2;
  return same || swapped;
}

bool OnOneWall(const Segment2& p, ClusterId p_id, const Segment2& q, ClusterId q_id,
               const FusionParams& params, const FreeSpaceGrid* free_space,
               std::vector<Vec2>* gap_samples, const FreeSpaceGrid* proof) {
  const double offset_m = params.wall_offset_m;
  if (NearIdentical(p, q, offset_m)) return true;  // b.
  // a. Collinear within delta and the offset, overlapping or within the gap.
  const double lp = p.length(), lq = q.length();
  const bool p_longer = lp > lq || (lp == lq && p_id < q_id);
  const Segment2& l = p_longer ? p : q;
  const Segment2& s = p_longer ? q : p;
  const double l_length = p_longer ? lp : lq;
  const double s_length = p_longer ? lq : lp;
  if (!(l_length > 0.0) || !(s_length > 0.0)) return false;
  const Vec2 u = l.direction() / l_length;
  const Vec2 v = s.direction() / s_length;
  if (std::abs(Cross(u, s.a - l.a)) > offset_m || std::abs(Cross(u, s.b - l.a)) > offset_m) {
    return false;
  }
  const double ta = u.dot(s.a - l.a), tb = u.dot(s.b - l.a);
  // c. S lies wholly in the offset band along L: a short piece whose direction
  // is poorly determined (a corner fragment) repeats the wall whatever its angle.
  if (std::min(ta, tb) >= 0.0 && std::max(ta, tb) <= l_length) return true;
  // Included angle in [0, pi/2]: |sin| <= sin(delta) with |cos| >= cos(delta).
  if (std::abs(Cross(u, v)) > std::sin(params.delta_rad) + kSlackM) return false;
  const double gap = std::max({0.0, std::min(ta, tb) - l_length, -std::max(ta, tb)});
  if (gap <= params.wall_gap_m) return true;
  if (free_space == nullptr || gap > params.wall_occluded_gap_m) return false;
  if (gap > params.wall_occluded_gap_ratio * s_length) return false;
  // An occlusion or a passage: join only if nothing on the gap was seen free.
  const double t0 = std::max(ta, tb) < 0.0 ? std::max(ta, tb) : l_length;
  const double t1 = std::max(ta, tb) < 0.0 ? 0.0 : std::min(ta, tb);
  FreeSpaceGrid::Probe probe(*free_space);
  if (AnySample(l.a, u, t0, t1, [&](const Vec2& x) { return probe.IsFree(x); })) {
    return false;
  }
  if (gap <= params.wall_proof_gap_m) {
    // A short unseen gap may be an opening seen through to clutter: join only
    // where an observation proved it occluded. The ends (a cell each) may
    // fall outside the proof: pieces' fitted ends are not the observed ones.
    if (proof == nullptr) return false;
    FreeSpaceGrid::Probe proven(*proof);
    const double trim = FreeSpaceGrid::kCellM;
    const auto unproven = [&](const Vec2& x) { return !proven.IsFree(x); };
    const bool missing = t1 - t0 > 2.0 * trim ? AnySample(l.a, u, t0 + trim, t1 - trim, unproven)
                                              : unproven(l.a + 0.5 * (t0 + t1) * u);
    if (missing) return false;
  }
  if (gap_samples != nullptr) {
    AnySample(l.a, u, t0, t1, [&](const Vec2& x) {
      gap_samples->push_back(x);
      return false;
    });
  }
  return true;
}

WallConsolidator::WallConsolidator(const FusionParams& params, uint32_t support_cap)
    : params_(params),
      support_cap_(support_cap),
      max_wall_pieces_(params.mode == FusionMode::kBounded ? params.max_wall_pieces
                                                           : std::numeric_limits<size_t>::max()),
      index_(kPieceStepM),
      candidates_(&index_, [this](ClusterId id) -> const Segment2* {
        auto it = pieces_.find(id);
        return it == pieces_.end() || it->second.retired ? nullptr : &it->second.fit.segment;
      }) {}

void WallConsolidator::TouchNeighboursIfOversized(ClusterId id) {
  if (!pieces_.at(id).oversized) return;
  for (ClusterId other : Neighbours(id)) touched_pieces_.push_back(other);
}

FreeSpaceGrid* WallConsolidator::EnableFreeSpace() {
  if (!free_space_ && params_.consolidate && params_.wall_occluded_gap_m > 0.0) {
    // Pieces filed so far were checked without evidence: none is pierced yet,
    // and the grid starts empty, so that still holds.
    free_space_ =
        std::make_unique<FreeSpaceGrid>(params_.wall_free_min_count, params_.evidence_range_m);
    // Neighbours() searches further with evidence (occluded gaps).
    all_neighbours_stale_ = true;
    candidates_.Clear();
    if (params_.wall_proof_gap_m > 0.0) {
      proof_ = std::make_unique<FreeSpaceGrid>(1, params_.evidence_range_m);
    }
    if (params_.retire_views > 0) {
      ledger_ = std::make_unique<RetirementLedger>(params_.retire_views, free_space_.get());
      // Pieces published before the first view: watched from now on, as if
      // supported now (nothing saw through them yet).
      for (const auto& [id, piece] : pieces_) {
        if (!piece.retired) ledger_->Watch(id, piece.fit.segment, true);
      }
    }
  }
  return free_space_.get();
}

void WallConsolidator::AddObservation(const Vec2& origin, const std::vector<Segment2>& segments) {
  if (EnableFreeSpace() == nullptr) return;
  for (const Segment2& s : segments) free_space_->AddView(origin, s);
  if (ledger_) RetireSeenThrough();
  if (!proof_) return;
  for (const Segment2& stretch : OccludedStretches(origin, segments, params_)) {
    proof_->AddLine(stretch);
  }
}

void WallConsolidator::Index(ClusterId id, const Segment2& s, bool insert) {
  if (insert) candidates_.Filed(id);
  for (const Vec2& p : FiledPoints(s)) {
    if (insert) {
      index_.Insert(p, id);
    } else {
      index_.EraseIf(p, [id](ClusterId x) { return x == id; });
    }
  }
}

void WallConsolidator::UpdatePiercing(Piece* piece, double shift_m) {
  if (free_space_ == nullptr) {
    piece->pierced = false;
    piece->pierce_clearance_m = 0.0;  // checked afresh once there is evidence
    return;
  }
  if (!piece->pierced && shift_m < piece->pierce_clearance_m) {
    piece->pierce_clearance_m -= shift_m;  // no sample reached a cell free at the check
    return;
  }
  const PierceCheck check = CheckPiercing(piece->fit.segment, *free_space_);
  piece->pierced = check.pierced;
  piece->pierce_clearance_m = check.clearance_m;
}

bool WallConsolidator::Upsert(const ClusterStats& stats, const ClusterStats::Fit& fit) {
  bool reindex = true;
  // How far its piercing samples moved (infinite: check afresh).
  double shift_m = std::numeric_limits<double>::infinity();
  bool supported = true;  // a new piece was just supported
  auto it = pieces_.find(stats.id);
  if (it != pieces_.end()) {
    const ClusterStats& old = piece_stats_.at(stats.id);
    if (old.member_count == stats.member_count && old.support() == stats.support() &&
        it->second.fit.segment.a == fit.segment.a && it->second.fit.segment.b == fit.segment.b) {
      return false;
    }
    // A regrouping by the chain guard can change a piece without a new
    // feature; only one that adds members or support is a sighting.
    supported = stats.member_count > old.member_count || stats.support() > old.support();
    Piece& piece = it->second;
    if (piece.retired) {
      piece.fit = fit;
      piece_stats_[stats.id] = stats;
      if (!supported) return true;  // still seen through: published nowhere
      piece.retired = false;        // seen again: back, as a new piece
      --retired_count_;
    } else {
      TouchNeighboursIfOversized(stats.id);
      reindex = !SameFiledCells(index_, piece.fit.segment, fit.segment);
      if (reindex) Index(stats.id, piece.fit.segment, false);
      if (piece.has_wall) touched_walls_.push_back(piece.wall);
      shift_m = SampleShiftBound(piece.fit.segment, fit.segment);
    }
    piece.fit = fit;
  } else {
    it = pieces_.emplace(stats.id, Piece()).first;
    it->second.fit = fit;
  }
  UpdatePiercing(&it->second, shift_m);
  piece_stats_[stats.id] = stats;
  if (reindex) Index(stats.id, fit.segment, true);
  if (ledger_) ledger_->Watch(stats.id, fit.segment, supported);
  touched_pieces_.push_back(stats.id);
  return true;
}

bool WallConsolidator::Settle(const ClusterStats& stats, const ClusterStats::Fit& fit,
                              double tolerance_m) {
  auto it = pieces_.find(stats.id);
  if (it == pieces_.end() || it->second.retired || !it->second.has_wall) return false;
  const Piece& piece = it->second;
  const ClusterStats& upserted = piece_stats_.at(stats.id);
  // A new robot changes the wall's robot list, which the caller's count
  // update does not recompute.
  if (stats.robots.size() != upserted.robots.size()) return false;
  const double tolerance_sq = tolerance_m * tolerance_m;
  if ((fit.segment.a - piece.fit.segment.a).squaredNorm() > tolerance_sq ||
      (fit.segment.b - piece.fit.segment.b).squaredNorm() > tolerance_sq) {
    return false;
  }
  // As Upsert would: a feature that adds members or support is a sighting.
  const bool supported =
      stats.member_count > upserted.member_count || stats.support() > upserted.support();
  if (ledger_) ledger_->Watch(stats.id, piece.fit.segment, supported);
  return true;
}

void WallConsolidator::RetireSeenThrough() {
  std::vector<ClusterId> changed;
  ledger_->AddPasses(free_space_->TakeWatchedPasses(), &changed);
  // The walls of the pieces with more cells seen through: each is retired
  // whole if its pieces' cells are, together, seen through on the fraction.
  std::vector<ClusterId> walls;
  for (ClusterId id : changed) {
    const Piece& piece = pieces_.at(id);
    if (piece.has_wall) walls.push_back(piece.wall);
  }
  std::sort(walls.begin(), walls.end());
  walls.erase(std::unique(walls.begin(), walls.end()), walls.end());
  for (ClusterId wall : walls) {
    auto it = walls_.find(wall);
    if (it == walls_.end()) continue;
    size_t cells = 0, seen = 0;
    for (ClusterId id : it->second.pieces) {
      const auto [piece_cells, piece_seen] = ledger_->SeenThrough(id);
      cells += piece_cells;
      seen += piece_seen;
    }
    if (cells == 0 ||
        static_cast<double>(seen) < params_.retire_fraction * static_cast<double>(cells)) {
      continue;
    }
    const std::vector<ClusterId> members = it->second.pieces;  // Retire() touches walls_'s wall
    for (ClusterId id : members) Retire(id);
  }
}

void WallConsolidator::Retire(ClusterId id) {
  Piece& piece = pieces_.at(id);
  if (piece.retired) return;
  TouchNeighboursIfOversized(id);
  Index(id, piece.fit.segment, false);
  if (piece.has_wall) touched_walls_.push_back(piece.wall);
  piece.has_wall = false;
  piece.retired = true;
  ++retired_count_;
  if (ledger_) ledger_->Unwatch(id);
  DropNeighbours(id);
  candidates_.Forget(id);
}

std::vector<ClusterId> WallConsolidator::RetiredPieces() const {
  std::vector<ClusterId> out;
  for (const auto& [id, piece] : pieces_) {
    if (piece.retired) out.push_back(id);
  }
  std::sort(out.begin(), out.end());
  return out;
}

void WallConsolidator::Erase(ClusterId piece) {
  auto it = pieces_.find(piece);
  if (it == pieces_.end()) return;
  if (it->second.retired) {
    --retired_count_;
    pieces_.erase(it);
    piece_stats_.erase(piece);
    return;
  }
  if (ledger_) ledger_->Unwatch(piece);
  TouchNeighboursIfOversized(piece);
  DropNeighbours(piece);
  Index(piece, it->second.fit.segment, false);
  if (it->second.has_wall) touched_walls_.push_back(it->second.wall);
  pieces_.erase(it);
  piece_stats_.erase(piece);
  candidates_.Forget(piece);
}

void WallConsolidator::SetVerifyNeighbourCache(bool on) { verify_neighbour_cache = on; }
size_t WallConsolidator::neighbour_cache_mismatches() { return neighbour_cache_mismatch_count; }
size_t WallConsolidator::piercing_mismatches() { return piercing_mismatch_count; }

void WallConsolidator::RefreshNeighbours(ClusterId id) {
  std::vector<ClusterId> now = Neighbours(id);
  std::vector<ClusterId>& cached = neighbours_[id];  // a node: stays valid as others are added
  for (ClusterId other : cached) {
    if (!std::binary_search(now.begin(), now.end(), other)) EraseSorted(&neighbours_[other], id);
  }
  for (ClusterId other : now) {
    if (!std::binary_search(cached.begin(), cached.end(), other)) {
      InsertSorted(&neighbours_[other], id);
    }
  }
  cached = std::move(now);
}

void WallConsolidator::DropNeighbours(ClusterId id) {
  auto it = neighbours_.find(id);
  if (it == neighbours_.end()) return;
  const std::vector<ClusterId> old = std::move(it->second);
  neighbours_.erase(it);
  for (ClusterId other : old) {
    if (auto o = neighbours_.find(other); o != neighbours_.end()) EraseSorted(&o->second, id);
  }
}

const std::vector<ClusterId>& WallConsolidator::CachedNeighbours(ClusterId id) {
  auto it = neighbours_.find(id);
  if (it == neighbours_.end()) {
    // Every live piece is refreshed when it appears; a miss is a bug, and the
    // search it stands for is still right.
    ++neighbour_cache_mismatch_count;
    RefreshNeighbours(id);
    it = neighbours_.find(id);
  } else if (verify_neighbour_cache && Neighbours(id, false, false) != it->second) {
    ++neighbour_cache_mismatch_count;
  }
  return it->second;
}

std::vector<ClusterId> WallConsolidator::Neighbours(ClusterId id, bool record_gaps,
                                                    bool cached_search) {
  std::vector<ClusterId> out;
  if (!params_.consolidate) return out;
  const Piece& piece = pieces_.at(id);
  if (piece.pierced) return out;
  const Segment2& s = piece.fit.segment;
  std::vector<SearchBand> bands;
  bands.reserve(3);  // (reserved: called for every refit piece, so allocations count)
  bands.push_back({s, params_.wall_offset_m + params_.wall_gap_m + 0.5 * kPieceStepM + kSlackM});
  const double length = s.length();
  if (free_space_ && params_.wall_occluded_gap_m > params_.wall_gap_m && length > 0.0) {
    // Occluded-gap candidates lie along the line: the nearer end of the other
    // (a filed point) within the gap of this one's extent, and off its line by
    // at most the offset plus what delta_rad turns over the gap.
    const double gap_m = params_.wall_occluded_gap_m;
    const double tan_delta = std::tan(std::min(params_.delta_rad, 1.5));
    const double along_m = (gap_m + params_.wall_offset_m) * (1.0 + tan_delta) + kSlackM;
    const Vec2 u = s.direction() / length;
    const double lateral_m =
        2.0 * params_.wall_offset_m + (gap_m + kPieceStepM) * tan_delta + kSlackM;
    // Beyond the two ends only: along the extent the band above finds them.
    bands.push_back({Segment2{s.a - along_m * u, s.a}, lateral_m});
    bands.push_back({Segment2{s.b, s.b + along_m * u}, lateral_m});
  }
  // The cache's candidates are kept below if a search of the bands would
  // find them: if they are filed in a cell of `exact`.
  std::vector<PieceIndex::SegmentBand> exact;
  if (cached_search) {
    exact.reserve(bands.size());
    for (const SearchBand& band : bands) {
      exact.push_back(index_.BandOf(band.segment, band.radius_m));
    }
    const std::vector<ClusterId>& candidates = candidates_.Candidates(id, bands);
    out.reserve(candidates.size());
    for (ClusterId other : candidates) {
      if (other == id) continue;
      auto it = pieces_.find(other);
      if (it == pieces_.end() || it->second.retired) continue;  // not filed
      out.push_back(other);
    }
  } else {
    out.reserve(32);  // a piece is filed every 2 m: long walls find each other many times
    for (const SearchBand& band : bands) {
      index_.ForEachNearSegment(band.segment, band.radius_m, [&](ClusterId other) {
        if (other != id) out.push_back(other);
      });
    }
    std::sort(out.begin(), out.end());
    out.erase(std::unique(out.begin(), out.end()), out.end());
  }
  std::vector<Vec2> gap_samples;
  out.erase(std::remove_if(out.begin(), out.end(),
                           [&](ClusterId other) {
                             const Piece& q = pieces_.at(other);
                             if (q.pierced) return true;
                             gap_samples.clear();
                             if (!OnOneWall(s, id, q.fit.segment, other, params_, free_space_.get(),
                                            record_gaps ? &gap_samples : nullptr, proof_.get())) {
                               return true;
                             }
                             // Last, as the dearer test: OnOneWall rejects most candidates.
                             if (cached_search && !FiledInBands(index_, q.fit.segment, exact)) {
                               return true;
                             }
                             // Bridged an occluded gap: watch its cells.
                             uint64_t last_key = 0;
                             for (size_t k = 0; k < gap_samples.size(); ++k) {
                               const uint64_t key = IndexCellKey(gap_samples[k]);
                               if (k > 0 && key == last_key) continue;
                               last_key = key;
                               std::vector<ClusterId>& ids = gap_watch_[key];
                               for (ClusterId z : {id, other}) {
                                 if (std::find(ids.begin(), ids.end(), z) == ids.end()) {
                                   ids.push_back(z);
                                 }
                               }
                             }
                             return false;
                           }),
            out.end());
  return out;
}

void WallConsolidator::TakeEvidence() {
  if (!free_space_) return;
  if (proof_) {
    // Newly proven cells can only join pieces across a gap of up to
    // wall_proof_gap_m: re-resolve every piece filed within reach of one.
    const double reach_m =
        0.5 * params_.wall_proof_gap_m + params_.wall_offset_m + 0.71 * kPieceStepM + kSlackM;
    uint64_t last_key = 0;
    bool has_last = false;
    for (uint64_t cell : proof_->TakeNewlyFree()) {
      const Vec2 centre = FreeSpaceGrid::CellCentre(cell);
      const uint64_t key = IndexCellKey(centre);
      if (has_last && key == last_key) continue;  // one query per run of cells in one index cell
      last_key = key;
      has_last = true;
      const Vec2 corner = FreeSpaceGrid::CellCentre(key) - Vec2(0.5, 0.5) * FreeSpaceGrid::kCellM;
      const Vec2 index_centre = (corner / FreeSpaceGrid::kCellM + Vec2(0.5, 0.5)) * kPieceStepM;
      index_.ForEachNear(index_centre, reach_m + 0.71 * kPieceStepM,
                         [&](ClusterId id) { touched_pieces_.push_back(id); });
    }
  }
  const std::vector<uint64_t> cells = free_space_->TakeNewlyFree();
  if (cells.empty()) return;
  // The new free cells by index cell.
  std::unordered_map<uint64_t, std::vector<Vec2>> by_index_cell;
  for (uint64_t cell : cells) {
    const Vec2 centre = FreeSpaceGrid::CellCentre(cell);
    by_index_cell[IndexCellKey(centre)].push_back(centre);
  }
  // A piece whose samples reach an index cell has a filed point within half
  // a filing step and half a cell diagonal of it: one query from the index
  // cell's centre, reaching half its diagonal further. A sample's cell centre
  // lies within half a cell diagonal of the piece's segment.
  // Pieces whose samples come within kPierceClearanceCapM of a new free
  // cell too: their clearance (piercing.h) may have shrunk.
  const double radius = 0.5 * kPieceStepM + 0.71 * kPieceStepM + 0.71 * FreeSpaceGrid::kCellM +
                        kPierceClearanceCapM + kSlackM;
  const double on_segment_m = 0.71 * FreeSpaceGrid::kCellM + kPierceClearanceCapM + kSlackM;
  std::vector<ClusterId> recheck;
  for (const auto& entry : by_index_cell) {
    // Not a structured binding: C++17 lambdas cannot capture those (clang refuses).
    const uint64_t key = entry.first;
    const std::vector<Vec2>& centres = entry.second;
    if (auto it = gap_watch_.find(key); it != gap_watch_.end()) {
      for (ClusterId id : it->second) {
        if (pieces_.count(id) != 0) touched_pieces_.push_back(id);
      }
      gap_watch_.erase(it);
    }
    const Vec2 corner = FreeSpaceGrid::CellCentre(key) - Vec2(0.5, 0.5) * FreeSpaceGrid::kCellM;
    const Vec2 centre = (corner / FreeSpaceGrid::kCellM + Vec2(0.5, 0.5)) * kPieceStepM;
    index_.ForEachNear(centre, radius, [&](ClusterId id) {
      // Cells only become free: a pierced piece stays pierced until it changes.
      const Piece& piece = pieces_.at(id);
      if (piece.pierced) return;
      for (const Vec2& c : centres) {
        if (geometry::PointSegmentDistance(c, piece.fit.segment) <= on_segment_m) {
          recheck.push_back(id);
          return;
        }
      }
    });
  }
  std::sort(recheck.begin(), recheck.end());
  recheck.erase(std::unique(recheck.begin(), recheck.end()), recheck.end());
  for (ClusterId id : recheck) {
    Piece& piece = pieces_.at(id);
    const PierceCheck check = CheckPiercing(piece.fit.segment, *free_space_);
    piece.pierce_clearance_m = check.clearance_m;
    if (!check.pierced) continue;
    TouchNeighboursIfOversized(id);
    piece.pierced = true;
    touched_pieces_.push_back(id);
  }
}

bool WallConsolidator::Twins(const std::vector<ClusterId>& component,
                             const std::vector<uint32_t>& head,
                             const std::vector<uint32_t>& tail) const {
  for (uint32_t i : head) {
    for (uint32_t j : tail) {
      if (NearIdentical(pieces_.at(component[i]).fit.segment, pieces_.at(component[j]).fit.segment,
                        params_.wall_offset_m)) {
        return true;
      }
    }
  }
  return false;
}

void WallConsolidator::WallsOf(const std::vector<ClusterId>& component,
                               std::vector<Wall>* walls) const {
  std::vector<std::vector<uint32_t>> groups;
  if (component.size() > 1 && params_.chain_max_rms_m > 0.0) {
    // The guard, with each piece standing for all its members' endpoints.
    std::vector<GuardMember> members;
    members.reserve(component.size());
    for (ClusterId id : component) {
      members.push_back({id, pieces_.at(id).fit.segment, &piece_stats_.at(id).moments});
    }
    groups = SplitChain(members, params_.chain_max_rms_m, params_.chain_max_sse_ratio,
                        [&](const std::vector<uint32_t>& head, const std::vector<uint32_t>& tail) {
                          return !Twins(component, head, tail);
                        });
  } else {
    groups.emplace_back(component.size());
    for (uint32_t i = 0; i < component.size(); ++i) groups.back()[i] = i;
  }
  for (const std::vector<uint32_t>& group : groups) {  // each ascending, as `component`
    Wall wall;
    wall.pieces.reserve(group.size());
    for (uint32_t i : group) wall.pieces.push_back(component[i]);
    if (group.size() == 1) {
      wall.single = &piece_stats_.at(component[group.front()]);
      wall.fit = pieces_.at(component[group.front()]).fit;
    } else {
      std::vector<const ClusterStats*> parts;
      parts.reserve(group.size());
      for (uint32_t i : group) parts.push_back(&piece_stats_.at(component[i]));
      wall.merged = ClusterStats::MergeAll(parts, support_cap_);
      wall.fit = wall.merged->Refit();
    }
    walls->push_back(std::move(wall));
  }
}

void WallConsolidator::Resolve(std::vector<ClusterId>* removed, std::vector<Wall>* walls) {
  removed->clear();
  walls->clear();
  TakeEvidence();
  if (verify_neighbour_cache && free_space_ != nullptr) {
    // Every touched piece's flag as a fresh check has it (piercing.h).
    for (ClusterId id : touched_pieces_) {
      auto it = pieces_.find(id);
      if (it == pieces_.end() || it->second.retired) continue;
      if (it->second.pierced != Pierced(it->second.fit.segment, *free_space_)) {
        ++piercing_mismatch_count;
      }
    }
  }
  const uint64_t walk = ++resolve_count_;
  // The walls recomputed: the touched ones and those the walk drags in
  // (marked affected_in; a wall missing from walls_ is listed, possibly more
  // than once, and goes as removed).
  std::vector<ClusterId> affected = touched_walls_;
  std::vector<ClusterId> work;
  work.reserve(2 * touched_pieces_.size() + 4 * touched_walls_.size());
  const auto live = [this](ClusterId id) {
    auto it = pieces_.find(id);
    return it != pieces_.end() && !it->second.retired;
  };
  for (ClusterId id : touched_pieces_) {
    if (live(id)) work.push_back(id);
  }
  for (ClusterId wall : touched_walls_) {
    auto it = walls_.find(wall);
    if (it == walls_.end() || it->second.affected_in == walk) continue;
    it->second.affected_in = walk;
    for (ClusterId id : it->second.pieces) {
      if (live(id)) work.push_back(id);
    }
  }
  // The neighbour cache first: a walk reads lists of untouched pieces, which
  // must already mirror every touched piece's change.
  std::vector<ClusterId> refresh;
  refresh.reserve(touched_pieces_.size());
  if (all_neighbours_stale_) {
    for (const auto& [id, piece] : pieces_) {
      if (!piece.retired) refresh.push_back(id);
    }
    all_neighbours_stale_ = false;
  } else {
    for (ClusterId id : touched_pieces_) {
      if (live(id)) refresh.push_back(id);
    }
  }
  std::sort(refresh.begin(), refresh.end());
  refresh.erase(std::unique(refresh.begin(), refresh.end()), refresh.end());
  for (ClusterId id : refresh) RefreshNeighbours(id);
  touched_pieces_.clear();
  touched_walls_.clear();

  // Connected components of OnOneWall from the touched pieces. A piece
  // reached that belonged to another wall drags that wall's pieces in too.
  // A walk stops past max_wall_pieces_ pieces, or on reaching a piece of an
  // oversized component found before: then every piece it reached is a wall
  // of its own, and so is every piece of the smaller components it swallowed
  // (found through pieces not oversized before, or touched).
  std::vector<ClusterId> touched = work;  // sorted: one allocation, not a node per piece
  std::sort(touched.begin(), touched.end());
  touched.erase(std::unique(touched.begin(), touched.end()), touched.end());
  const auto was_touched = [&touched](ClusterId id) {
    return std::binary_search(touched.begin(), touched.end(), id);
  };
  // Whether this walk reached `id` before; marks it reached.
  const auto reached = [&](ClusterId id) {
    Piece& piece = pieces_.at(id);
    const bool before = piece.reached_in == walk;
    piece.reached_in = walk;
    return before;
  };
  const auto mark_oversized = [&](ClusterId id) { pieces_.at(id).oversized_in = walk; };
  const auto oversized_now = [&](ClusterId id) { return pieces_.at(id).oversized_in == walk; };
  std::vector<std::vector<ClusterId>> components;
  std::vector<ClusterId> singles;  // pieces of oversized components reached
  const auto drag = [&](ClusterId id) {
    const Piece& piece = pieces_.at(id);
    if (!piece.has_wall) return;
    auto it = walls_.find(piece.wall);
    if (it == walls_.end()) {
      affected.push_back(piece.wall);
    } else if (it->second.affected_in != walk) {
      it->second.affected_in = walk;
      affected.push_back(piece.wall);
      work.insert(work.end(), it->second.pieces.begin(), it->second.pieces.end());
    }
  };
  std::vector<ClusterId> stack;
  for (size_t next = 0; next < work.size(); ++next) {
    if (reached(work[next])) continue;
    std::vector<ClusterId> component;
    stack.assign(1, work[next]);
    bool oversized = false;
    while (!stack.empty() && !oversized) {
      const ClusterId id = stack.back();
      stack.pop_back();
      component.push_back(id);
      drag(id);
      if (component.size() > max_wall_pieces_) {
        oversized = true;
        break;
      }
      for (ClusterId other : CachedNeighbours(id)) {
        if (!reached(other)) {
          stack.push_back(other);
        } else if (oversized_now(other)) {
          oversized = true;
        }
      }
    }
    if (!oversized) {
      std::sort(component.begin(), component.end());
      components.push_back(std::move(component));
      continue;
    }
    for (ClusterId id : stack) {
      component.push_back(id);
      drag(id);
    }
    std::vector<ClusterId> expand;
    for (ClusterId id : component) {
      mark_oversized(id);
      if (!pieces_.at(id).oversized || was_touched(id)) expand.push_back(id);
    }
    while (!expand.empty()) {
      const ClusterId id = expand.back();
      expand.pop_back();
      for (ClusterId other : CachedNeighbours(id)) {
        // An untouched piece oversized before stays a wall of its own.
        if (pieces_.at(other).oversized && !was_touched(other)) continue;
        if (reached(other)) continue;
        component.push_back(other);
        mark_oversized(other);
        drag(other);
        expand.push_back(other);
      }
    }
    singles.insert(singles.end(), component.begin(), component.end());
  }

  std::sort(affected.begin(), affected.end());
  affected.erase(std::unique(affected.begin(), affected.end()), affected.end());
  // At most a wall per piece: no reallocation moves the walls' statistics.
  size_t most_walls = singles.size();
  for (const std::vector<ClusterId>& component : components) most_walls += component.size();
  walls->reserve(most_walls);
  for (const std::vector<ClusterId>& component : components) {
    WallsOf(component, walls);
    for (ClusterId id : component) pieces_.at(id).oversized = false;
  }
  std::sort(singles.begin(), singles.end());
  for (ClusterId id : singles) {
    WallsOf({id}, walls);
    pieces_.at(id).oversized = true;
  }
  std::vector<ClusterId> now;  // the walls' ids (a single's is its own)
  now.reserve(walls->size());
  for (const Wall& wall : *walls) now.push_back(wall.stats().id);
  std::sort(now.begin(), now.end());
  // The affected walls gone; the others' members are overwritten in place
  // (their lists' storage reused).
  for (ClusterId wall : affected) {
    if (std::binary_search(now.begin(), now.end(), wall)) continue;
    walls_.erase(wall);
    removed->push_back(wall);  // ascending, as `affected`
  }
  // Record membership: every piece of a component belongs to one of its walls.
  for (const Wall& wall : *walls) {
    const ClusterId id = wall.stats().id;
    walls_[id].pieces = wall.pieces;
    for (ClusterId piece_id : wall.pieces) {
      Piece& piece = pieces_.at(piece_id);
      piece.wall = id;
      piece.has_wall = true;
    }
  }
}

}  // namespace mapd::fusion
