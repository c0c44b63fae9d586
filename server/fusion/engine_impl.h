// FusionEngine's internals, shared by engine.cc (the algorithm) and
// engine_state.cc (snapshots). Not part of the API: include engine.h.
#ifndef MAPD_FUSION_ENGINE_IMPL_H_
#define MAPD_FUSION_ENGINE_IMPL_H_

#include <algorithm>
#include <map>
#include <memory>
#include <unordered_map>
#include <unordered_set>
#include <vector>

#include "fusion/chain_guard.h"
#include "fusion/cluster_stats.h"
#include "fusion/corner_snap.h"
#include "fusion/engine.h"
#include "fusion/grid_index.h"
#include "fusion/support_counter.h"
#include "fusion/wall_consolidation.h"
#include "geometry/box2.h"

namespace mapd::fusion {

using geometry::Segment2;
using geometry::Vec2;

// Cell size of the feature-centre grid. Queries cover R_f + eta, so cells of
// the order of a typical wall segment keep both the probed cell count and the
// per-cell candidate count small.
constexpr double kFeatureCellM = 1.0;

// Bounded mode: a cluster is "established" once this many distinct
// observations (at least min_support) saw it. Only established clusters fold
// new features, and their support is exact up to here (support_counter.h).
// Young clusters keep every member as in exact mode: their links are the
// fragile ones (docs/long-running.md: folding into young clusters
// changed the map of a real log, folding into established ones did not).
constexpr uint32_t kEstablishedSupport = 32;

// Bounded mode: cell size of the representatives' centre grid that cover
// lookups probe (radius cover_m, a few centimetres): fine cells keep the
// candidates to the near-duplicates, where the 1 m cells of the link grid
// would hold every representative of a metre of wall.
constexpr double kCoverCellM = 0.1;

// A representative as filed in the cover grid, its segment inline: every
// raw feature probes this grid, and reading the segment from anchors_ was a
// cache miss per candidate (a third of FindCover's time in a city soak).
struct CoverItem {
  Segment2 segment;
  uint32_t node;
};

// A raw feature as filed in the centre grid: what the criteria need, inline,
// so that a candidate scan touches one cache line per candidate.
struct IndexedFeature {
  Segment2 segment;
  Vec2 centre;
  double radius_m;
  uint32_t node;
};

// A published wall's counts: what a settled piece changes (its geometry and
// robots stay).
struct WallCounts {
  uint32_t member_count = 0;
  uint32_t plane_members = 0;
  uint32_t support = 0;
  double z_min_m = 0.0;
  double z_max_m = 0.0;
  // Writes them into f; returns whether any differed.
  bool Set(FusedFeature* f) const;
};

class FusionEngine::Impl {
 public:
  explicit Impl(const FusionParams& params)
      : params_(params),
        guard_on_(params.chain_max_rms_m > 0.0),
        bounded_(params.mode == FusionMode::kBounded),
        support_cap_(bounded_ ? std::max(kEstablishedSupport, params.min_support)
                              : SupportCounter::kUnlimited),
        grid_(kFeatureCellM),
        cover_grid_(kCoverCellM),
        snapper_(params.snap_m, params.corner_mode, params.corner_pairing),
        consolidator_(params, support_cap_) {}

  Status Validate(ObservationId observation, const std::vector<GroundFeature>& features) const;
  // sensor_xy_m: null if unknown (no free-space evidence).
  void Add(ObservationId observation, RobotId robot, const Vec2* sensor_xy_m,
           const std::vector<GroundFeature>& features, ChangeFeed* changes);
  std::optional<FusedFeature> Get(ClusterId id) const;

  const FusionParams params_;
  const bool guard_on_;         // chain guard (chain_guard.h) enabled
  const bool bounded_;          // FusionMode::kBounded: nodes are representatives
  const uint32_t support_cap_;  // exact support up to this many observations
  // A node is a raw feature (exact mode) or a representative (bounded mode:
  // the first feature of it, plus every later one folded into it).
  std::unordered_set<ObservationId> observations_;  // exact mode only
  ObservationId last_observation_ = 0;
  bool has_last_observation_ = false;
  std::unordered_map<FeatureId, uint32_t> node_of_;  // by the node's own feature id
  // Union-find over nodes; stats_ is non-null at roots only.
  std::vector<uint32_t> parent_;
  std::vector<uint32_t> size_;
  std::vector<std::unique_ptr<ClusterStats>> stats_;
  // Bounded mode, valid at roots: the bounding box of the component's member
  // endpoints (= of its hull, which is how a snapshot restores it).
  std::vector<geometry::Box2> bounds_;
  size_t cluster_count_ = 0;        // components
  uint64_t raw_feature_count_ = 0;  // features added, folded ones included
  // Per node, kept when the guard is on or in bounded mode: the node's own
  // feature (the guard refits subsets; snapshots refile the grid from it).
  std::vector<GroundFeature> anchors_;
  // Guard on: where each node's own feature came from.
  std::vector<ObservationId> observation_of_;
  std::vector<RobotId> robot_of_;
  // Guard on, bounded mode: the statistics of a representative that has
  // folded features in (its own feature included); null while it has none,
  // so that a map seen once costs no more than in exact mode.
  std::vector<std::unique_ptr<ClusterStats>> folded_;
  // Guard on: the next member of the node's component (a circular list per
  // component: a union splices two lists in O(1)).
  std::vector<uint32_t> next_member_;
  // Components the guard cut into more than one group, by component id: the
  // ids of their published groups and their group count.
  struct SplitRecord {
    std::vector<ClusterId> published;
    uint32_t group_count = 0;
  };
  std::unordered_map<ClusterId, SplitRecord> split_;
  size_t extra_groups_ = 0;  // sum over split_ of (group_count - 1)
  UniformGrid<IndexedFeature> grid_;
  UniformGrid<CoverItem> cover_grid_;  // bounded mode: representatives by centre
  CornerSnapper snapper_;
  // The published clusters (the guard's groups at min_support) are the
  // consolidator's pieces; what is published is its walls.
  WallConsolidator consolidator_;
  std::map<ClusterId, FusedFeature> published_;  // walls, ascending id: Published() is a copy

  bool keeps_anchors() const { return guard_on_ || bounded_; }
  uint32_t FindConst(uint32_t x) const;  // no path compression, for const readers
  // Whether the guard may cut the component at `root` (else it is one group).
  bool MayCut(uint32_t root) const {
    return guard_on_ && ChainMayNeedSplit(stats_[root]->moments, params_.chain_max_rms_m);
  }
  // The guard's groups of the component at `root`, as member nodes and stats.
  std::vector<std::vector<uint32_t>> GroupNodes(uint32_t root) const;
  ClusterStats StatsOf(const std::vector<uint32_t>& nodes) const;
  // StatsOf({nodes[i] : i in subset}).support() >= min_support, cheaply.
  bool ReachesMinSupport(const std::vector<uint32_t>& nodes,
                         const std::vector<uint32_t>& subset) const;
  // Guard on: everything node `n` stands for (its feature, and in bounded
  // mode what was folded into it).
  ClusterStats NodeStats(uint32_t n) const {
    if (bounded_ && folded_[n]) return *folded_[n];
    return ClusterStats::OfFeature(anchors_[n], observation_of_[n], robot_of_[n]);
  }
  // Files node `node`, whose own feature is `segment`, in the centre grid.
  void FileInGrid(uint32_t node, const Segment2& segment);
  // A piece's statistics now: its component's if it is the component's one
  // group (the consolidator's copy may be older: a settled piece), else the
  // consolidator's (always current for the groups of a cut component).
  const ClusterStats& CurrentStats(ClusterId piece) const;
  // The counts of a wall of `pieces` (ascending) from their current
  // statistics, merged as ClusterStats::MergeAll does.
  WallCounts CurrentCounts(const std::vector<ClusterId>& pieces) const;

 private:
  uint32_t Find(uint32_t x);
  // Returns the surviving root; records the ids of both clusters in `merged_ids`.
  uint32_t Union(uint32_t a, uint32_t b, std::vector<ClusterId>* merged_ids);
  bool MayLink(uint32_t a, uint32_t b) const;
  uint32_t NewNode(const GroundFeature& f, ObservationId observation, RobotId robot);
  // Bounded mode: the representative `f` folds into (both endpoints within
  // cover_m, criteria met; the nearest, ties by node), or false.
  bool FindCover(const GroundFeature& f, uint32_t* node) const;
  void LinkToEarlier(uint32_t node, const GroundFeature& f, std::vector<ClusterId>* merged_ids);
  // `grown`: the roots of `roots` that gained a node (ascending).
  void Publish(const std::vector<uint32_t>& roots, const std::vector<uint32_t>& grown,
               const std::vector<ClusterId>& merged_ids, ChangeFeed* feed);
  // Hands one group (support >= min_support) to the consolidator.
  void PublishGroup(const ClusterStats& stats) { consolidator_.Upsert(stats, stats.Refit()); }
  // The same for a component that is one group and grew only by folds,
  // unless its piece settles (FusionParams::refit_tolerance_m): then its id is
  // appended to `settled`.
  void PublishFolded(const ClusterStats& whole, std::vector<ClusterId>* settled);
  // Publishes one wall unless it is unchanged; one whose fitted segment did
  // not move but whose counts did is appended to `recounted` instead of the
  // feed (the caller adds it to feed->updated after the corner pass).
  void PublishWall(const WallConsolidator::Wall& wall, ChangeFeed* feed,
                   std::vector<Vec2>* moved_points, std::vector<ClusterId>* recounted);
};

}  // namespace mapd::fusion

#endif  // MAPD_FUSION_ENGINE_IMPL_H_
