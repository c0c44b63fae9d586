// FusionEngine snapshots (engine.h: SaveState / LoadState).
//
// Layout, little-endian, doubles as their IEEE bits so that a restored engine
// continues bit for bit:
//   "MAPDFUS1" | u32 version | params key (string) | body | u64 checksum of all before
//   (version 3: WordChecksum; version 2, the same layout: FNV-1a)
//   body: nodes (parent, size, anchor, next member, folded stats, root stats),
//         counters, split records, published features, the snapper's lines,
//         the consolidator's pieces, whether it has free-space evidence and
//         its tiles.
// The grid and the snapper's index are refiled from the nodes, in node order
// (the order the live engine filed them), so candidate scans visit the same
// items in the same order.
#include <algorithm>
#include <cstring>
#include <string>

#include "fusion/engine_impl.h"
#include "fusion/state_codec.h"

namespace mapd::fusion {
namespace {

constexpr char kMagic[8] = {'M', 'A', 'P', 'D', 'F', 'U', 'S', '1'};
// 2: the consolidator's pieces. Retirement's section (retired pieces, the
// ledger) follows the evidence only when the params key has retirement on,
// so the layout without it is unchanged.
// 3: closed by WordChecksum instead of FNV-1a (version 2 is still read).
constexpr uint32_t kVersion = 3;
constexpr SnapshotFormat kFormats[] = {{2, SnapshotChecksum::kFnv1a},
                                       {kVersion, SnapshotChecksum::kWords}};

class Writer : public StateWriter {
 public:
  using StateWriter::StateWriter;
  void V2(const Vec2& v) {
    F64(v.x());
    F64(v.y());
  }
  void Seg(const Segment2& s) {
    V2(s.a);
    V2(s.b);
  }
  void Feature(const GroundFeature& f) {
    U64(f.id);
    Seg(f.segment);
    F64(f.z_min_m);
    F64(f.z_max_m);
    U8(f.origin == FeatureOrigin::kPlane ? 1 : 0);
  }
  void Stats(const ClusterStats& s) {
    U64(s.id);
    U32(s.member_count);
    U32(s.plane_members);
    U64(s.moments.count);
    V2(s.moments.mean);
    for (int i = 0; i < 4; ++i) F64(s.moments.scatter(i));
    U64(s.hull.size());
    for (const Vec2& p : s.hull) V2(p);
    F64(s.z_min_m);
    F64(s.z_max_m);
    Ids(s.observations.ids());
    U32(s.observations.saturated_count());
    U64(s.observations.last());
    Ids(s.robots);
  }
};

class Reader : public StateReader {
 public:
  using StateReader::StateReader;
  Vec2 V2() {
    const double x = F64();
    return Vec2(x, F64());
  }
  Segment2 Seg() {
    const Vec2 a = V2();
    return {a, V2()};
  }
  GroundFeature Feature() {
    GroundFeature f;
    f.id = U64();
    f.segment = Seg();
    f.z_min_m = F64();
    f.z_max_m = F64();
    f.origin = U8() != 0 ? FeatureOrigin::kPlane : FeatureOrigin::kLine;
    return f;
  }
  ClusterStats Stats() {
    ClusterStats s;
    s.id = U64();
    s.member_count = U32();
    s.plane_members = U32();
    s.moments.count = U64();
    s.moments.mean = V2();
    for (int i = 0; i < 4; ++i) s.moments.scatter(i) = F64();
    s.hull.resize(Count(16));
    for (Vec2& p : s.hull) p = V2();
    s.z_min_m = F64();
    s.z_max_m = F64();
    std::vector<uint64_t> ids = Ids();
    const uint32_t saturated = U32();
    const uint64_t last = U64();
    s.observations = SupportCounter::FromState(std::move(ids), saturated, last);
    s.robots = Ids();
    return s;
  }
};

Status Corrupt(const std::string& what) {
  return Status::InvalidArgument("fusion snapshot is corrupt: " + what);
}

}  // namespace

Status FusionEngine::SaveState(std::string* out) const {
  const Impl& e = *impl_;
  if (!e.bounded_) return Status::Unimplemented("snapshots are for fusion.mode = bounded");
  out->clear();
  Writer w(out);
  out->append(kMagic, sizeof(kMagic));
  w.U32(kVersion);
  w.Str(FusionParamsKey(e.params_));
  const size_t n = e.parent_.size();
  w.U64(n);
  for (size_t i = 0; i < n; ++i) {
    w.U32(e.parent_[i]);
    w.U32(e.size_[i]);
    w.Feature(e.anchors_[i]);
    if (e.guard_on_) {
      w.U32(e.next_member_[i]);
      w.U64(e.observation_of_[i]);
      w.U64(e.robot_of_[i]);
      w.U8(e.folded_[i] ? 1 : 0);
      if (e.folded_[i]) w.Stats(*e.folded_[i]);
    }
    w.U8(e.stats_[i] ? 1 : 0);
    if (e.stats_[i]) w.Stats(*e.stats_[i]);
  }
  w.U64(e.cluster_count_);
  w.U64(e.raw_feature_count_);
  w.U64(e.last_observation_);
  w.U8(e.has_last_observation_ ? 1 : 0);
  // By id: the map's iteration order depends on its insertion history, and
  // equal engines must give equal bytes (a restored engine's map was filled
  // in another order).
  std::vector<ClusterId> split_ids;
  split_ids.reserve(e.split_.size());
  for (const auto& entry : e.split_) split_ids.push_back(entry.first);
  std::sort(split_ids.begin(), split_ids.end());
  w.U64(e.split_.size());
  for (ClusterId id : split_ids) {
    const Impl::SplitRecord& record = e.split_.at(id);
    w.U64(id);
    w.U32(record.group_count);
    w.Ids(record.published);
  }
  w.U64(e.extra_groups_);
  w.U64(e.published_.size());
  for (const auto& [id, f] : e.published_) {
    w.U64(f.id);
    w.Seg(f.segment);
    w.Seg(f.fitted);
    w.F64(f.z_min_m);
    w.F64(f.z_max_m);
    w.U32(f.support);
    w.U32(f.member_count);
    w.U32(f.plane_members);
    w.Ids(f.robots);
    Segment2 fitted;
    geometry::Line2 line;
    e.snapper_.Lookup(id, &fitted, &line);
    w.Seg(fitted);
    w.V2(line.point);
    w.V2(line.direction);
  }
  // The consolidator's pieces; its walls are a function of them (Resolve).
  w.U64(e.consolidator_.pieces().size());
  for (const auto& [id, stats] : e.consolidator_.pieces()) w.Stats(stats);
  // Free-space evidence: whether there is any, and its tiles ascending by key.
  // Written only with the evidence on (the params key says so), so that
  // snapshots without it keep their layout.
  const bool evidence_on = e.params_.consolidate && e.params_.wall_occluded_gap_m > 0.0;
  const FreeSpaceGrid* free_space = e.consolidator_.free_space();
  if (evidence_on) w.U8(free_space != nullptr ? 1 : 0);
  const auto write_tiles = [&w](const FreeSpaceGrid& grid) {
    const auto tiles = grid.SortedTiles();
    w.U64(tiles.size());
    for (const auto& [key, tile] : tiles) {
      w.U64(key);
      w.Str(std::string_view(reinterpret_cast<const char*>(tile->data()), tile->size()));
    }
  };
  if (free_space != nullptr) {
    write_tiles(*free_space);
    // The proofs of occlusion exist with the evidence when wall_proof_gap_m > 0
    // (in the params key, so the layout follows from the params).
    if (e.consolidator_.proof() != nullptr) write_tiles(*e.consolidator_.proof());
    // Retirement, with the evidence (the params key says whether it is on).
    if (const RetirementLedger* ledger = e.consolidator_.ledger(); ledger != nullptr) {
      w.Ids(e.consolidator_.RetiredPieces());
      w.U64(ledger->entries().size());
      for (const auto& [id, entry] : ledger->entries()) {
        w.U64(id);
        w.Seg(entry.segment);
        w.Str(entry.passes);
      }
    }
  }
  w.U64(WordChecksum(*out));
  return Status::Ok();
}

StatusOr<std::unique_ptr<FusionEngine>> FusionEngine::LoadState(const FusionParams& params,
                                                                std::string_view state) {
  MAPD_RETURN_IF_ERROR(params.Validate());
  if (params.mode != FusionMode::kBounded) {
    return Status::Unimplemented("snapshots are for fusion.mode = bounded");
  }
  // A snapshot taken without settled walls (refit_tolerance_m 0, as every
  // release before it) is a state a settling engine can continue from: all
  // its pieces are current. The reverse is not (a settled piece's copy is
  // older than its cluster), so only this direction.
  std::vector<std::string> keys = {FusionParamsKey(params)};
  if (params.refit_tolerance_m > 0.0) {
    FusionParams every_refit = params;
    every_refit.refit_tolerance_m = 0.0;
    keys.push_back(FusionParamsKey(every_refit));
  }
  StatusOr<std::string_view> payload =
      OpenSnapshot(state, std::string_view(kMagic, sizeof(kMagic)), {kFormats[0], kFormats[1]},
                   keys, "fusion snapshot");
  if (!payload.ok()) return payload.status();
  Reader r(*payload);
  auto engine = std::make_unique<FusionEngine>(params);
  Impl& e = *engine->impl_;
  const uint64_t n = r.Count(4 + 4 + 49 + 1);
  e.parent_.resize(n);
  e.size_.resize(n);
  e.bounds_.resize(n);
  e.anchors_.resize(n);
  e.stats_.resize(n);
  if (e.guard_on_) {
    e.next_member_.resize(n);
    e.observation_of_.resize(n);
    e.robot_of_.resize(n);
    e.folded_.resize(n);
  }
  for (uint64_t i = 0; i < n && r.ok(); ++i) {
    e.parent_[i] = r.U32();
    e.size_[i] = r.U32();
    e.anchors_[i] = r.Feature();
    if (e.guard_on_) {
      e.next_member_[i] = r.U32();
      e.observation_of_[i] = r.U64();
      e.robot_of_[i] = r.U64();
      if (r.U8() != 0) e.folded_[i] = std::make_unique<ClusterStats>(r.Stats());
    }
    if (r.U8() != 0) e.stats_[i] = std::make_unique<ClusterStats>(r.Stats());
    e.bounds_[i] = geometry::Box2{};
    if (e.stats_[i] && !e.stats_[i]->hull.empty()) {
      geometry::Box2& box = e.bounds_[i];
      box.min = box.max = e.stats_[i]->hull.front();
      for (const Vec2& p : e.stats_[i]->hull) {
        box.min = box.min.cwiseMin(p);
        box.max = box.max.cwiseMax(p);
      }
    }
  }
  e.cluster_count_ = r.U64();
  e.raw_feature_count_ = r.U64();
  e.last_observation_ = r.U64();
  e.has_last_observation_ = r.U8() != 0;
  const uint64_t splits = r.Count(20);
  for (uint64_t i = 0; i < splits && r.ok(); ++i) {
    const ClusterId id = r.U64();
    Impl::SplitRecord record;
    record.group_count = r.U32();
    record.published = r.Ids();
    e.split_[id] = std::move(record);
  }
  e.extra_groups_ = r.U64();
  const uint64_t published = r.Count(8);
  std::vector<std::pair<ClusterId, std::pair<Segment2, geometry::Line2>>> lines;
  for (uint64_t i = 0; i < published && r.ok(); ++i) {
    FusedFeature f;
    f.id = r.U64();
    f.segment = r.Seg();
    f.fitted = r.Seg();
    f.z_min_m = r.F64();
    f.z_max_m = r.F64();
    f.support = r.U32();
    f.member_count = r.U32();
    f.plane_members = r.U32();
    f.robots = r.Ids();
    Segment2 fitted = r.Seg();
    geometry::Line2 line;
    line.point = r.V2();
    line.direction = r.V2();
    lines.push_back({f.id, {fitted, line}});
    e.published_[f.id] = std::move(f);
  }
  const uint64_t pieces = r.Count(8);
  std::vector<ClusterStats> piece_stats;
  for (uint64_t i = 0; i < pieces && r.ok(); ++i) {
    piece_stats.push_back(r.Stats());
    if (!r.ok()) break;
    if (piece_stats.back().hull.empty() || piece_stats.back().moments.count == 0)
      return Corrupt("an empty published cluster");
  }
  // The evidence before the pieces: whether a piece is pierced depends on it.
  const bool evidence_on = params.consolidate && params.wall_occluded_gap_m > 0.0;
  bool has_ledger = false;
  std::vector<ClusterId> retired;
  struct LedgerEntry {
    ClusterId id;
    Segment2 segment;
    std::string passes;
  };
  std::vector<LedgerEntry> ledger_entries;
  if (evidence_on && r.U8() != 0) {
    FreeSpaceGrid* free_space = e.consolidator_.EnableFreeSpace();
    if (free_space == nullptr) return Corrupt("free-space evidence with it off");
    const auto read_tiles = [&r](FreeSpaceGrid* grid) {
      const uint64_t tiles = r.Count(8 + 8 + sizeof(FreeSpaceGrid::Tile));
      uint64_t previous_key = 0;
      for (uint64_t i = 0; i < tiles && r.ok(); ++i) {
        const uint64_t key = r.U64();
        const std::string bytes = r.Str();
        if (!r.ok()) break;
        if (bytes.size() != sizeof(FreeSpaceGrid::Tile) || (i > 0 && key <= previous_key)) {
          return false;
        }
        previous_key = key;
        FreeSpaceGrid::Tile tile;
        std::memcpy(tile.data(), bytes.data(), tile.size());
        grid->RestoreTile(key, tile);
      }
      return true;
    };
    if (!read_tiles(free_space)) return Corrupt("a free-space tile");
    FreeSpaceGrid* proof = e.consolidator_.mutable_proof();
    if (proof != nullptr && !read_tiles(proof)) return Corrupt("a proof-of-occlusion tile");
    has_ledger = e.consolidator_.ledger() != nullptr;
    if (has_ledger) {
      retired = r.Ids();
      const uint64_t entries = r.Count(8 + 32 + 8);
      for (uint64_t i = 0; i < entries && r.ok(); ++i) {
        const uint64_t id = r.U64();
        const Segment2 segment = r.Seg();
        ledger_entries.push_back({id, segment, r.Str()});
      }
    }
  }
  if (!r.ok() || !r.at_end()) return Corrupt("truncated or trailing bytes");
  for (const ClusterStats& stats : piece_stats) e.consolidator_.Upsert(stats, stats.Refit());
  if (has_ledger) {
    // Upsert watched every piece afresh: retire and restore what the live one had.
    for (ClusterId id : retired) {
      if (!e.consolidator_.HasPiece(id)) return Corrupt("a retired piece that is not a piece");
      e.consolidator_.Retire(id);
    }
    RetirementLedger* ledger = e.consolidator_.mutable_ledger();
    for (const LedgerEntry& entry : ledger_entries) {
      if (!e.consolidator_.HasPiece(entry.id) || !ledger->Watches(entry.id) ||
          !ledger->Restore(entry.id, entry.segment, entry.passes)) {
        return Corrupt("a retirement entry");
      }
    }
    if (ledger->entries().size() != ledger_entries.size()) return Corrupt("retirement entries");
  }

  // Structure: indices in range, stats exactly at roots, shallow trees.
  size_t roots = 0;
  for (uint64_t i = 0; i < n; ++i) {
    if (e.parent_[i] >= n || (e.guard_on_ && e.next_member_[i] >= n)) {
      return Corrupt("node " + std::to_string(i) + " points outside the snapshot");
    }
    const bool root = e.parent_[i] == i;
    if (root != (e.stats_[i] != nullptr)) return Corrupt("cluster statistics off the roots");
    roots += root;
    uint32_t x = static_cast<uint32_t>(i);
    for (int depth = 0; e.parent_[x] != x; ++depth) {
      if (depth > kMaxForestDepth) return Corrupt("a cycle in the cluster forest");
      x = e.parent_[x];
    }
  }
  if (roots != e.cluster_count_) return Corrupt("cluster count disagrees with the forest");

  // Refile the indexes, in node order (as the live engine filed them).
  for (uint32_t i = 0; i < n; ++i) {
    e.node_of_.emplace(e.anchors_[i].id, i);
    e.FileInGrid(i, e.anchors_[i].segment);
  }
  for (const auto& [id, fl] : lines) e.snapper_.Upsert(id, fl.first, fl.second);
  std::vector<ClusterId> removed_walls;
  std::vector<WallConsolidator::Wall> walls;
  e.consolidator_.Resolve(&removed_walls, &walls);
  if (walls.size() != e.published_.size()) {
    return Corrupt("published features disagree with the published clusters");
  }
  for (const WallConsolidator::Wall& wall : walls) {
    if (e.published_.count(wall.stats().id) == 0) {
      return Corrupt("published features disagree with the published clusters");
    }
  }
  return engine;
}

}  // namespace mapd::fusion
