// Merging voxel submaps without an initial pose (docs/algorithms.md part B):
// corners -> matching -> alignment (Umeyama, then ICP on the overlap) ->
// occupancy fusion; for more than two submaps, pairwise merges and a spanning
// tree of the best accepted edges. This is the one entry point the service uses.
//
// Thread safety: the functions are reentrant. A merge may take seconds; the
// progress callback is called on the caller's thread.
//
// The measurements behind the defaults below, and the merge's current
// figures on real maps: docs/voxel-merge.md.
#ifndef MAPD_VOXEL_MERGE_H_
#define MAPD_VOXEL_MERGE_H_

#include <Eigen/Geometry>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "common/status.h"
#include "voxel/corner_extraction.h"
#include "voxel/corner_matching.h"
#include "voxel/correlation_search.h"
#include "voxel/gravity_alignment.h"
#include "voxel/icp.h"
#include "voxel/occupancy_fusion.h"  // FusionRule, ResolutionPolicy (exact rules there)
#include "voxel/octree_reader.h"

namespace mapd::voxel {

// Angular tolerances of one corner-matching stage (CornerMatchingParams).
struct MatchTolerances {
  double signature_deg = 10.0;  // signature_tolerance_rad, in degrees
  double normal_deg = 6.0;      // normal_tolerance_rad, in degrees
};

struct MergeParams {
  // Evidence needed to accept a pairwise merge; below it the merge is refused
  // with FailedPrecondition and a reason, and nothing is written.
  int min_matched_corners = 4;
  // RMS after ICP, in voxels of the COARSER map of the pair (the same unit
  // when both have one resolution: a right 10 cm / 5 cm merge ends at 0.43
  // coarse voxels, 0.87 fine ones). Two rasterisations of one surface in
  // rotated grids leave ~0.5 voxel; right merges of the real-map benchmark
  // end at 0.50-0.63, the closest wrong ones at 0.81 and above
  // (docs/voxel-merge.md, "Residuals of right and wrong hypotheses"). Maps
  // noisier than rasterisations (different sensors) may need more.
  double max_residual_voxels = 0.75;
  // Overlap score (voxel/merge_overlap.h): of B's occupied voxels that land on
  // space A has observed (free or occupied), the share that lands on (or
  // within one voxel of) an occupied voxel of A. B's voxels in A's unknown
  // space count neither way. Calibrated on generated maps only: correct
  // merges of the furnished room (tests) and of geb079.bt with a moved copy of
  // itself score 1.0; that copy 0.5 m off scores 0.66; wrong cliques that
  // flip the room by ~180 deg so that its walls coincide scored 0.48-0.88.
  double min_overlap_score = 0.9;
  // Support: B's occupied voxels that coincide with A's (the overlap score's
  // numerator), as a share of B's evaluated voxels. The overlap score alone
  // accepts a placement that touches A only at a wall or a room corner (a
  // few hundred voxels, all coinciding): the correlation generator proposed
  // such placements of the test rooms at 2-4 % support while the true ones
  // had 40-100 %. The benchmark's 10 % overlap crops have ~10 %.
  double min_support_fraction = 0.05;
  // Shared free space, when both maps carry free space (voxel/merge_overlap.h
  // SharedFree): B's free voxels that land on A's free space, per B voxel
  // that coincides with A's. Support and overlap pass a placement that puts
  // B's wall on A's wall with B's room on the far side, in A's unknown space
  // (a generated half-room next door to the other: residual 0.21 voxels,
  // overlap 1.00, support 0.10); both maps saw the space in front of the
  // walls of a right merge, and neither in such a placement. 0 = off.
  double min_shared_free_ratio = 1.0;
  FusionRule fusion_rule = FusionRule::kOverlapRule;
  ResolutionPolicy resolution_policy = ResolutionPolicy::kRefuse;
  // Budget for one merge, checked between stages and pairs (ResourceExhausted
  // naming the stage); also caps the corner search of each pair.
  double max_seconds = 60.0;
  // Threads one merge may use (the caller's included): the inputs are read
  // and viewed, the plan view's yaw candidates scored, the correlation's FFT
  // passes run, ICP's restarts scored and the maps read for fusion in
  // parallel. The result does not depend on it (tests compare 1 to 4).
  // 1: single-threaded. mapd sets it from
  // merge.threads and runs limits.max_concurrent_merges merges at once, so a
  // merge queues rather than oversubscribes the cores.
  int threads = 1;

  // The stages' own parameters (lengths in voxels of each map unless _m).
  CornerExtractionParams corners;
  // matching.consistency_distance_m is replaced by consistency_distance_voxels
  // times the finest resolution; max_search_seconds by the remaining budget
  // when that is smaller. top_k is raised from 8 to 32: in rooms most corners
  // are Manhattan (three right angles), the signatures cannot tell them apart,
  // and with 8 partners per corner the true pairs of a furnished room were
  // pruned and a wrong 7-match clique won over the true 8 (tests/voxel/merge_test.cc).
  // max_candidate_pairs 12,000 bounds the graph of maps with ~1000 corners
  // (fr_078_tidyup: matching 4.6 s -> 1.0 s median, no trial lost).
  CornerMatchingParams matching = [] {
    CornerMatchingParams p;
    p.top_k = 32;
    p.max_candidate_pairs = 12'000;
    return p;
  }();
  double consistency_distance_voxels = 2.0;  // D of the paper's eq. (4)
  // Corner solutions tried per pair. When alignment refuses the maximum clique
  // (residual or overlap), its pairs are excluded and the search is run again:
  // on symmetric buildings the largest clique is sometimes a wrong (about
  // 180 deg) correspondence while the right one is a little smaller
  // (docs/voxel-merge.md). Every solution must pass the same gates.
  // max_match_attempts solutions are tried with `matching`'s tolerances, then
  // as many with each of `looser_tolerances` in turn (a new graph each time).
  int max_match_attempts = 3;
  // Why looser stages: on real maps the three normals of one physical corner,
  // seen in two submaps, differ by 5-30 deg (the plane triple chosen at a
  // corner of four or more faces differs, and small faces fit badly), so the
  // strict signature and direction tests drop most true pairs (geb079: 49 B
  // corners within D of their true partner, 12 of them among the candidates).
  // Loose tolerances keep them but make the graph denser, so they are tried
  // only after the strict graph's solutions were refused (docs/voxel-merge.md).
  std::vector<MatchTolerances> looser_tolerances = {{25.0, 15.0}, {40.0, 30.0}};
  // ICP must converge to be accepted; from a corner solution tens of degrees
  // off, point-to-point ICP on new_college took 85 iterations (IcpParams: 50).
  IcpParams icp = [] {
    IcpParams p;
    p.max_iterations = 150;
    return p;
  }();
  // Each corner solution is first refined on icp_screen_points source points
  // (0 = no screen); it goes on to the full ICP only if that ends with a
  // residual within icp_screen_residual_factor x max_residual_voxels.
  // Measured on new_college.bt (docs/voxel-merge.md): most of a merge's time
  // went to full ICPs of solutions that were then refused.
  std::size_t icp_screen_points = 2'000;
  double icp_screen_residual_factor = 1.5;
  // The screen's iterations (at most icp.max_iterations). The full ICP goes
  // on from where the screen ended, so the cap only decides how far a start
  // may drift before it is judged: 60 decided every benchmark merge as no cap
  // did, at less CPU; 30 refused a right one (docs/voxel-merge.md).
  int icp_screen_iterations = 60;
  // Local uniqueness, the last gate: ICP is restarted from the answer turned
  // by +-restart_turn_deg about each axis (about the centre of B's voxels in
  // A's box), on icp_screen_points points, and, only if those spread beyond
  // the limit, on to the full ICP. If a restart that ends within
  // max_residual_voxels lies more than max_restart_spread_voxels (voxels of
  // the coarser map) from the answer at a corner of B's bounding box, the
  // overlap does not fix the alignment and the pair is refused (0 = off).
  // Why: the uniqueness gate only sees rivals 3 deg or 4 voxels apart, and a
  // low-overlap pair can have several ICP minima closer than that, one of
  // them wrong; right merges' restarts end within 4 voxels
  // (docs/archive/voxel-merge-history.md, "Larger samples").
  double restart_turn_deg = 1.5;
  double max_restart_spread_voxels = 4.0;
  // A converged ICP answer within this many degrees of a lattice pose (right
  // angles and whole voxels, voxel/lattice_pose.h; maps of one resolution)
  // is replaced by the best lattice pose around it when that fits at least
  // as well (ICP's residual, as many inliers). geb079.bt merged with itself
  // ended 0.76 voxel off the identity without it (residual 0.63 voxel), and
  // with it exactly on (residual 0). 0 = off.
  double lattice_snap_deg = 0.5;
  // B's voxels scored per candidate transform in the corner search's tie-break
  // (the paper: the transform making the most voxels coincide); 0 = all.
  std::size_t tie_break_points = 20'000;
  // B's voxels scored for acceptance; 0 = all.
  std::size_t overlap_points = 200'000;
  // Voxel-level work on free space per fused submap (occupancy_fusion.h).
  std::uint64_t max_fusion_free_voxels = 8'000'000;

  // The second hypothesis generator (docs/algorithms.md B.9): levelling and
  // yaw from floor and wall planes, translations by FFT correlation. Its
  // hypotheses go through the same ICP screen, ICP and gates.
  GravityParams gravity;
  CorrelationParams correlation;
  // Uniqueness gate: two hypotheses that both pass every gate and differ by
  // more than distinct_rotation_deg or distinct_translation_voxels (at B's
  // centroid) make the pair ambiguous, and it is refused naming both. Two
  // ICPs of one right answer end within 0.1 deg / 1 voxel of each other on
  // the benchmark; wrong answers on symmetric buildings are 90 or 180 deg
  // off, or a corridor bay (metres) along.
  double distinct_rotation_deg = 3.0;
  double distinct_translation_voxels = 4.0;
  // A distinct second hypothesis makes the pair ambiguous only when its
  // support is at least this share of the best one's (the best = the most
  // support): a symmetric building's twin has the same support, a placement
  // that shares one room corner with A has a fraction of it.
  double ambiguous_support_ratio = 0.5;
  // ... or when its overlap score is at least this much higher than the
  // best one's, whatever its support: it puts fewer of B's surfaces on space
  // A saw as free. A corridor's 180 deg flip can end with more support than
  // the truth (its walls coincide with A's) while putting B's boxes in A's
  // free space; the truth is then no rival by support alone (the generated
  // corridor of merge_test.cc; docs/voxel-merge.md).
  double ambiguous_overlap_margin = 0.02;
  // Corner solutions tried after an accepted one (its pairs excluded) to look
  // for a distinct second one. Each costs a clique search and an ICP screen.
  int uniqueness_corner_attempts = 1;

  Status Validate() const;
};

// One input: the bytes of a .bt or .ot file (untrusted: parsed by ReadOctree).
struct SubmapInput {
  uint64_t id = 0;
  std::string_view bytes;
};

// One submap read, checked and viewed for merging (PrepareSubmaps): its tree,
// its voxel grid and its levelling, and what merges compute of it later
// (corners, overlap and ICP indexes), kept for the next merge of it. That is
// all a merge spends on each input alone (0.5-0.7 s of one core for a campus
// crop of 150k occupied voxels): a service that prepares a submap when it is
// uploaded spares every merge of it that time (docs/voxel-merge.md,
// "Prepared submaps"). Not thread-safe: one merge at a time may use it.
class PreparedSubmap {
 public:
  struct Parts;  // merge.cc
  explicit PreparedSubmap(std::unique_ptr<Parts> parts);
  ~PreparedSubmap();
  PreparedSubmap(const PreparedSubmap&) = delete;
  PreparedSubmap& operator=(const PreparedSubmap&) = delete;

  uint64_t id() const;
  // Heap bytes it holds, approximately (a cache's measure); grows as merges
  // add corners and indexes.
  std::size_t MemoryBytes() const;
  Parts& parts() { return *parts_; }

 private:
  std::unique_ptr<Parts> parts_;
};

// One corner pair of the evidence that placed a submap: the same physical
// corner seen in the submap and in the submap it was matched against, the
// latter carried into the reference frame. Metres.
struct MatchedCorner {
  Eigen::Vector3d in_submap = Eigen::Vector3d::Zero();
  Eigen::Vector3d in_reference = Eigen::Vector3d::Zero();
};

// Where submap `id` sits in the merged map's frame (= the first input's frame).
struct Alignment {
  uint64_t id = 0;
  Eigen::Isometry3d T_reference_submap = Eigen::Isometry3d::Identity();
  int matched_corners = 0;
  double residual_m = 0.0;     // RMS after refinement, metres
  double overlap_score = 0.0;  // [0, 1]
  // The generator of the tree edge that placed it (PairReport::source and
  // by_corners); empty and false for the first input.
  std::string source;
  bool by_corners = false;
  // The rest of that edge's gate figures (PairReport; -1 where not measured,
  // and for the first input): for operators judging a merge, how far each
  // gate was from refusing it, and how close the runner-up came.
  double support_fraction = -1.0;
  double shared_free_ratio = -1.0;
  double restart_spread_voxels = -1.0;
  double second_residual_m = -1.0;
  // The corner pairs of the tree edge that placed it (matched_corners of
  // them); empty for the first input. T_reference_submap maps in_submap onto
  // in_reference up to the corners' own error (ICP refined past them).
  std::vector<MatchedCorner> matched;
};

// Wall-clock seconds. alignment_s = ICP + overlap scores; fusion_s includes
// writing the .bt bytes; reading_s = parsing the inputs (ReadOctree + grid).
// correlation_s = levelling, yaw and FFT translation search (their ICPs count
// in alignment_s).
struct StageTimes {
  double corners_s = 0, matching_s = 0, alignment_s = 0, fusion_s = 0, correlation_s = 0;
  double reading_s = 0, total_s = 0;
};

// One pairwise merge attempt (every pair of inputs is tried).
// One hypothesis of a pair as its refinement ended (PairReport::hypotheses).
struct HypothesisReport {
  std::string label;  // the generator's, e.g. "plan view yaw 58.6 deg"
  Eigen::Isometry3d T_a_b = Eigen::Isometry3d::Identity();
  // Refused by the ICP screen: residual_m is the screen's, on
  // MergeParams::icp_screen_points of B's voxels, and no later gate ran.
  bool screened = false;
  double residual_m = 0.0;  // 0 when ICP failed (reason says why)
  double overlap_score = 0.0;
  double support_fraction = 0.0;
  bool accepted = false;  // passed every gate of its own (not the uniqueness gate)
  std::string reason;     // why refused; empty when accepted
};

struct PairReport {
  uint64_t id_a = 0, id_b = 0;
  bool accepted = false;
  std::string reason;  // why it was refused, e.g. "only 2 matched corners, need 4"
  Eigen::Isometry3d T_a_b = Eigen::Isometry3d::Identity();
  int matched_corners = 0;
  double residual_m = 0.0;
  double overlap_score = 0.0;
  double support_fraction = 0.0;  // see MergeParams::min_support_fraction
  // See MergeParams::min_shared_free_ratio; -1 when not measured (a map
  // without free space, or a hypothesis refused by an earlier gate).
  double shared_free_ratio = -1.0;
  int icp_iterations = 0;
  // See MergeParams::max_restart_spread_voxels; -1 when not measured (gate
  // off, or a hypothesis refused by an earlier gate).
  double restart_spread_voxels = -1.0;
  // T_a_b is a lattice pose (MergeParams::lattice_snap_deg), not ICP's own
  // answer: right angles and whole voxels.
  bool on_lattice = false;
  // Which generator gave T_a_b: "corner solution N", "correlation ...",
  // "plan view ..." or "the 180 deg turn of ...".
  std::string source;
  // Whether that generator was corner matching: only then do matched_corners
  // count (the others have no corners of their own; they pass the same
  // residual, overlap, free-space and uniqueness gates).
  bool by_corners = false;
  // The best hypothesis distinct from T_a_b (uniqueness gate thresholds) that
  // reached ICP: its residual, overlap score and support, -1 / 0 / 0 when
  // there was none.
  // The margin of the answer: a second hypothesis near the gates is a warning.
  double second_residual_m = -1.0;
  double second_overlap_score = 0.0;
  double second_support_fraction = 0.0;
  int hypotheses_tried = 0;        // corner solutions + correlation hypotheses refined
  int corner_solutions_tried = 0;  // clique searches run
  int correlation_hypotheses = 0;  // correlation peaks generated (0 = not run)
  // The matched corners (positions in A's and in B's frame, metres), set
  // whenever matched_corners is.
  std::vector<std::pair<Eigen::Vector3d, Eigen::Vector3d>> matched_a_b;
  // residual_m is an ICP screen's (see HypothesisReport::screened).
  bool screened = false;
  // Every hypothesis that reached ICP, in the order refined (corner
  // solutions, then the correlation generator's; the 180 deg twin last):
  // how close right and wrong ones come to the gates (tests/bench's
  // voxel_residuals_diag).
  std::vector<HypothesisReport> hypotheses;
};

struct MergeOutcome {
  std::vector<Alignment> alignments;  // one per input, in input order; the first is the identity
  std::string merged_bt;              // the merged map as an OctoMap .bt file
  uint64_t occupied_voxels = 0;
  StageTimes times;
  std::vector<PairReport> pairs;  // every pair tried, accepted or not
  // Corners found per input, in input order; -1 where none were extracted
  // (the correlation generator placed every pair of that submap).
  std::vector<int64_t> corners;
  double resolution = 0.0;  // of the merged map, metres
  // Free voxels left out of the fusion by max_fusion_free_voxels (left unknown).
  uint64_t free_voxels_skipped = 0;
  // The tree merged_bt was written from (an octomap::OcTree), held so that
  // the caller chooses when to pay for freeing it: ~0.15 s of one core for a
  // campus pair. mapd frees it once the answer is handed over, while the
  // handler stores the merge. Freed with the outcome otherwise.
  std::shared_ptr<void> merged_tree;
};

// The evidence of a merge looked at again, one rule for every caller (the
// service before it stores a merge, the benchmark before it counts one): one
// alignment per input; every placed input within max_residual_voxels of the
// finest of `resolutions_m` (the inputs', in input order) and at
// min_overlap_score; one placed by corner matching (Alignment::by_corners)
// with min_matched_corners; a merged map. A bug in the search must not be
// stored as a merge. FailedPrecondition naming the submap and the figure that
// failed; Internal for a malformed outcome.
Status CheckMergeEvidence(const MergeOutcome& outcome, const std::vector<double>& resolutions_m,
                          const MergeParams& params);

// What a merge's answer means, decided in one place for every caller (the
// service's MergeSubmaps, which the web view and mapctl reach; the
// benchmark): refused (the search's own refusal or CheckMergeEvidence's), or
// accepted, or proposed when `review` (an operator approves it later).
enum class MergeVerdict { kRefused, kAccepted, kProposed };
struct MergeDecision {
  MergeVerdict verdict = MergeVerdict::kRefused;
  Status reason;  // why refused; Ok otherwise
  // Accepted or proposed: where input i (in `ids` order) sits in the first
  // input's frame. The frame ties they imply: geometry::FramesOfMerge.
  std::vector<Eigen::Isometry3d> T_ref_input;
};
// outcome: MergeSubmaps's answer for the inputs `ids` (the first is the
// reference) of resolutions `resolutions_m`, params as it ran with.
MergeDecision DecideMerge(const StatusOr<MergeOutcome>& outcome, const std::vector<uint64_t>& ids,
                          const std::vector<double>& resolutions_m, const MergeParams& params,
                          bool review);

// stage: "corners", "matching", "alignment", "fusion"; fraction in [0, 1] of the whole merge.
using ProgressCallback = std::function<void(const std::string& stage, double fraction)>;

// Merges two or more submaps. Errors: InvalidArgument (a malformed file, fewer
// than two inputs), FailedPrecondition (no corners, no overlap, weak evidence,
// mismatched resolutions under kRefuse: the message says which and why),
// ResourceExhausted (a map beyond the limits, or max_seconds exceeded).
//
// Every pair of inputs is matched (corners, max clique, Umeyama), refined by
// ICP and checked against the thresholds. When no corner solution passes, the
// correlation generator (levelling, wall yaw, FFT translation search;
// docs/algorithms.md B.9) proposes more starts for the same ICP and gates;
// two distinct accepted hypotheses of similar support refuse the pair as
// ambiguous (the uniqueness gate). The accepted pairs are the edges of
// a graph weighted by matched corners (overlap score breaks ties); every
// submap is placed in the first input's frame along its maximum spanning tree
// and fused in breadth-first order from the first. A submap not connected to
// the first makes the whole merge FailedPrecondition, naming every such
// submap and why its pairs were refused. Nothing is merged then.
StatusOr<MergeOutcome> MergeSubmaps(const std::vector<SubmapInput>& inputs,
                                    const MergeParams& params,
                                    const ProgressCallback& progress = {});

// Reads and views the inputs (ReadOctree, the voxel grid, and the levelling
// when the correlation generator runs first), one per thread up to
// params.threads. The views hold params' corner and levelling settings: merge
// them (MergePreparedSubmaps) with params that differ at most elsewhere.
// Errors: MergeSubmaps's for a malformed or oversized input, naming it.
StatusOr<std::vector<std::shared_ptr<PreparedSubmap>>> PrepareSubmaps(
    const std::vector<SubmapInput>& inputs, const MergeParams& params);

// MergeSubmaps on prepared inputs, decided exactly as on their bytes (the
// same steps on the same views). The inputs are not freed: they keep what
// this merge computed of them, so the caller may keep them for the next
// merge. MergeOutcome::times.reading_s is 0 (their reading was earlier).
StatusOr<MergeOutcome> MergePreparedSubmaps(
    const std::vector<std::shared_ptr<PreparedSubmap>>& inputs, const MergeParams& params,
    const ProgressCallback& progress = {});

}  // namespace mapd::voxel

#endif  // MAPD_VOXEL_MERGE_H_
