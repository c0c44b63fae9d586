// Parameters of the three-criteria feature fusion (docs/algorithms.md part A;
// the feature-fusion paper, Li et al. 2023, section 3). One validated struct; units in names.
#ifndef MAPD_FUSION_PARAMS_H_
#define MAPD_FUSION_PARAMS_H_

#include <cstdint>
#include <string>

#include "common/status.h"

namespace mapd::fusion {

enum class CornerMode {
  kMidpoint,      // the paper: snapped endpoints meet at their midpoint
  kIntersection,  // the intersection of the two fused lines (falls back to midpoint)
};

// Which endpoints snap together (corner_snap.h; docs/fusion.md, "Corner pairing").
enum class CornerPairing {
  kMutualNearest,  // e and e' snap iff each is the other's nearest: local, the default
  kGreedy,         // walls in id order, each free endpoint takes its nearest free one
};

// How the engine keeps a cluster's members (engine.h).
enum class FusionMode {
  // Every raw feature stays a member a new feature is tested against: exactly
  // the paper's batch result, whatever the arrival order, but the cost of one
  // observation and the memory grow with how often its walls were seen. The
  // reference.
  kExact,
  // A new feature whose endpoints lie within cover_m of an earlier
  // representative of its cluster is folded into that representative's
  // statistics and not kept: the work per observation and the memory depend
  // on the map, not on the length of history. The default.
  kBounded,
};

struct FusionParams {
  FusionMode mode = FusionMode::kBounded;
  // Bounded mode: a feature whose two endpoints each lie within cover_m of the
  // matching endpoints of a representative it meets the criteria with is
  // folded into it, metres. 0 folds exact duplicates only.
  double cover_m = 0.02;
  // Limits on the work one feature can cause, whatever came before
  // (docs/reliability.md, "Fusion cost per observation"; issue 46). Bounded
  // mode only: the exact mode is the unbounded reference.
  //
  // A link is not made if it would give a component of more than
  // max_component_nodes representatives that the chain guard has to regroup
  // (its endpoints further than chain_max_rms_m from one line): the guard
  // regroups a whole component each time an observation touches it, in
  // O(n log n) per cut. Junk (random walls all over a site) chained such
  // components across the map, and every later observation paid for them
  // (139,000 -> 1,400 fused features per CPU-second). A straight wall, which
  // the guard never regroups, may grow past the cap. On the real logs the
  // largest regrouped component had 1,038 representatives; 256 changes the
  // published map there by at most 5 % (docs/fusion-real-data.md). In
  // [16, 1048576].
  uint32_t max_component_nodes = 256;
  // Earlier representatives one new feature is compared with at most, in
  // its link search and (separately) its fold search: whole grid cells in a
  // fixed order, so which are left out depends on the map, not on arrival
  // order. The real logs need at most 1,467. In [16, 1048576].
  uint32_t max_link_candidates = 4096;
  // Wall consolidation joins the pieces (published clusters) of a connected
  // component of at most this many; the pieces of a larger one are each a
  // wall of their own (the paper's output for them). Consolidation re-walks
  // a component each time a piece of it changes: one robot sending 20 m walls
  // along a 200 km line made a component of thousands of long pieces, and
  // fusion fell from 126,000 to 5,000 features per CPU-second (issue 46). In
  // [16, 1048576].
  uint32_t max_wall_pieces = 256;
  // No wall is longer than this, metres: a longer feature is refused (Add),
  // and a link is not made that would give a component a wider extent (the
  // diagonal of its endpoints' bounding box). A straight component is never
  // regrouped, so nothing else bounds it: a robot sending one line over and
  // over along a 200 km strip made a single 200 km wall whose every update
  // rewrote the consolidation index along its length (issue 46). In both
  // modes for features, bounded mode for links. In [1, 1e6].
  double max_wall_length_m = 1000.0;
  double delta_rad = 5.0 * 3.14159265358979323846 / 180.0;  // criterion 1: max included angle
  // Criterion 2: min feature-circle overlap ratio, in [0, 1]. 0 is allowed (criterion 2
  // off): the engine's candidate search is bounded by criterion 3, not by the circles.
  double gamma = 0.3;
  double eta_m = 0.3;        // criterion 3: max centre-to-segment distance, metres
  uint32_t min_support = 3;  // observations a cluster needs to be published
  double snap_m = 0.5;       // corner optimisation: endpoints closer than this meet
  CornerMode corner_mode = CornerMode::kIntersection;
  CornerPairing corner_pairing = CornerPairing::kMutualNearest;
  double max_plane_tilt_rad = 10.0 * 3.14159265358979323846 / 180.0;  // vertical-plane test
  // Chain guard (chain_guard.h; docs/algorithms.md A.11):
  // a cluster whose member endpoints lie farther than chain_max_rms_m (RMS
  // orthogonal distance to its fitted line, metres) is published as pieces cut
  // along its length, each cut kept only if it leaves less than
  // chain_max_sse_ratio of the squared residual. 0 = off (the paper's method).
  double chain_max_rms_m = 0.05;
  double chain_max_sse_ratio = 0.5;  // in [0, 1]; 0 never cuts
  // Wall consolidation (wall_consolidation.h; docs/algorithms.md A.11), beyond
  // the paper: published clusters on one wall (within delta_rad and wall_offset_m,
  // overlapping or separated by at most wall_gap_m along it) are published as
  // one feature. false = the paper's output, one feature per cluster.
  bool consolidate = true;
  double wall_gap_m = 0.3;  // metres
  // Consolidation's lateral tolerance, metres: tighter than eta_m, because
  // pieces of one wall agree to a few centimetres while parallel surfaces a
  // decimetre or more apart (a shelf before a wall) are different features
  // (docs/fusion-real-data.md measures 0.05-0.3).
  double wall_offset_m = 0.1;
  // Consolidation with free-space evidence (free_space.h): pieces separated by
  // more than wall_gap_m and at most wall_occluded_gap_m join if no cell of the
  // gap on the wall line was observed free (an occlusion, not a passage), and
  // a piece whose own extent crosses an observed-free stretch (a grazing-angle
  // segment spanning a passage) joins nothing. Only observations added with a
  // sensor origin (FusionEngine::AddFrom) give evidence; an engine that has
  // none behaves as with 0 = off. docs/fusion.md measures the defaults
  // (occlusions of 4-13 m on the synthetic city).
  double wall_occluded_gap_m = 15.0;
  // ... and only if that gap is at most this many times the shorter piece's
  // length. An unseen stretch is not proof of a wall: on real indoor logs, a
  // 3 m piece would otherwise be drawn 12 m across a room nobody looked into
  // (docs/fusion-real-data.md); a long facade behind a fence keeps its join.
  double wall_occluded_gap_ratio = 3.0;  // in (0, 1000]
  // Visibility triangles that must cover a cell before it counts as observed
  // free, in [1, 255]. One: a join across a stretch a ray passed through draws
  // a wall where the robots saw none (issue 40; on the real logs 5 left 4-12 m
  // more wall on seen-through cells), while a wrongly free cell only costs a
  // join (a wall published in two pieces).
  uint32_t wall_free_min_count = 1;
  // ... and a gap up to this long joins only where an observation proved it
  // occluded: one that saw both pieces with a segment of its own in front of
  // the gap (occlusion_proof.h). Indoors an unseen gap of a few metres is
  // more often a doorway or a crossing corridor seen through to clutter (which
  // leaves no segment, so no visibility triangle) than an occlusion (issue 40,
  // docs/fusion-real-data.md). Metres, in [0, 1000]; 0: no proof needed.
  double wall_proof_gap_m = 4.0;
  // Free-space evidence reaches at most this far from the sensor along
  // either axis (a visibility triangle is clipped to that square): a valid
  // but absurd view (a 2 km wall 1 km away) would otherwise write millions
  // of cells. Lasers indoors see 30-80 m; the synthetic city, 40 m. Metres,
  // in (0, 1000].
  double evidence_range_m = 80.0;
  // Retirement (wall_retirement.h; docs/algorithms.md A.12): a published
  // piece that observations saw through since it was last supported leaves
  // the published map, and comes back when a feature supports it again. A
  // cell of its fitted segment (0.5 m trimmed at each end) is seen through
  // once retire_views observations' visibility triangles covered it since
  // the last support; the piece retires when at least retire_fraction of its
  // cells are. Needs the free-space evidence (wall_occluded_gap_m > 0).
  // 0 = off. In [0, 255].
  uint32_t retire_views = 10;
  double retire_fraction = 0.5;  // in (0, 1]
  // Settled walls (docs/algorithms.md A.5), bounded mode (the exact mode is
  // the reference): a published cluster whose refit
  // moves neither endpoint of its fitted segment by more than this, metres,
  // and adds no robot, keeps the geometry it was last consolidated with; only
  // its counts (members, support, height range) are updated. Every folded
  // feature refits its cluster, and on an established wall the refit moves
  // by micrometres (96 % of refits by < 0.1 mm on the synthetic city), yet
  // re-resolving the wall and its corners cost half of the fusion. The
  // published geometry is thus within this of the exact refit. 0: every
  // refit re-resolves (results as before). In [0, 0.05].
  double refit_tolerance_m = 0.001;

  // InvalidArgument naming the offending field if any value is out of range
  // (negative thresholds, gamma outside [0, 1], non-finite values, ...).
  Status Validate() const;
};

// Every parameter that changes the fused map, as text ("mode=bounded
// cover_m=0.02 ..."), doubles to 17 digits: equal texts, equal results. Kept
// with snapshots of the engine, which are only loaded with the same text.
std::string FusionParamsKey(const FusionParams& params);

// "exact" / "bounded".
const char* FusionModeName(FusionMode mode);
Status ParseFusionMode(const std::string& name, FusionMode* mode);

// "midpoint" / "intersection".
const char* CornerModeName(CornerMode mode);
Status ParseCornerMode(const std::string& name, CornerMode* mode);

// "mutual" / "greedy".
const char* CornerPairingName(CornerPairing pairing);
Status ParseCornerPairing(const std::string& name, CornerPairing* pairing);

}  // namespace mapd::fusion

#endif  // MAPD_FUSION_PARAMS_H_
