#include "voxel/merge.h"

#include <octomap/OcTree.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <optional>
#include <set>
#include <string>
#include <utility>

#include "common/clock.h"
#include "voxel/merge_graph.h"
#include "voxel/merge_pair.h"
#include "voxel/octree_reader.h"
#include "voxel/parallel.h"
#include "voxel/submap_features.h"
#include "voxel/voxel_grid.h"

namespace mapd::voxel {

// The params are a copy, so that the features (which point to them) stay
// valid as long as the view does.
struct PreparedSubmap::Parts {
  MergeParams params;
  uint64_t id = 0;
  OcTreePtr tree;
  VoxelGrid grid;
  std::optional<SubmapFeatures> features;  // set once grid is
};

PreparedSubmap::PreparedSubmap(std::unique_ptr<Parts> parts) : parts_(std::move(parts)) {}
PreparedSubmap::~PreparedSubmap() = default;
uint64_t PreparedSubmap::id() const { return parts_->id; }

std::size_t PreparedSubmap::MemoryBytes() const {
  std::size_t bytes = sizeof(Parts) + parts_->grid.MemoryBytes();
  if (parts_->tree != nullptr) {
    // OcTree::memoryUsage() counts 16 bytes a node and 64 a child array;
    // malloc gives them 32- and 80-byte chunks (measured: the heap grows by
    // this to within 1 %, 1.7x memoryUsage()).
    const std::size_t nodes = parts_->tree->calcNumNodes();
    const std::size_t inner = nodes - parts_->tree->getNumLeafNodes();
    bytes += 32 * nodes + 80 * inner;
  }
  if (parts_->features.has_value()) bytes += parts_->features->MemoryBytes();
  return bytes;
}

namespace {

using Clock = std::chrono::steady_clock;

std::string Metres(double value) {
  char buffer[64];
  std::snprintf(buffer, sizeof(buffer), "%g m", value);
  return buffer;
}

std::string Name(uint64_t id) { return "submap " + std::to_string(id); }

// Progress over the stages: corners 0-0.4, matching and alignment 0.4-0.8,
// fusion 0.8-1.
class Progress {
 public:
  explicit Progress(const ProgressCallback& callback) : callback_(callback) {}
  void Report(const std::string& stage, double fraction) const {
    if (callback_) callback_(stage, std::clamp(fraction, 0.0, 1.0));
  }

 private:
  const ProgressCallback& callback_;
};

Status OverBudget(Clock::time_point start, const MergeParams& params, const char* stage) {
  if (SecondsSince(start) <= params.max_seconds) return Status::Ok();
  return Status::ResourceExhausted(
      "merge exceeded max_seconds = " + std::to_string(params.max_seconds) + " s during " + stage);
}

// Why `node` has no accepted edge to the tree: its refused pairs.
std::string RefusalsOf(uint64_t id, const std::vector<PairReport>& pairs) {
  std::string out;
  for (const auto& pair : pairs) {
    if (pair.accepted || (pair.id_a != id && pair.id_b != id)) continue;
    if (!out.empty()) out += "; ";
    out += "with " + Name(pair.id_a == id ? pair.id_b : pair.id_a) + ": " + pair.reason;
  }
  return out;
}

// InvalidArgument for fewer than two inputs or an id given twice.
Status CheckInputIds(const std::vector<uint64_t>& input_ids) {
  if (input_ids.size() < 2) {
    return Status::InvalidArgument("a merge needs at least two submaps, got " +
                                   std::to_string(input_ids.size()));
  }
  std::set<uint64_t> ids;
  for (uint64_t id : input_ids) {
    if (!ids.insert(id).second) return Status::InvalidArgument(Name(id) + " is given twice");
  }
  return Status::Ok();
}

// The merge proper, on views of every input. `release`: the views are the
// merge's own, freed as soon as each part is done with (the peak is lower).
StatusOr<MergeOutcome> MergeViews(const std::vector<PreparedSubmap::Parts*>& submaps,
                                  const MergeParams& params,
                                  const ProgressCallback& progress_callback,
                                  Clock::time_point start, double reading_s, bool release);

}  // namespace

StatusOr<std::vector<std::shared_ptr<PreparedSubmap>>> PrepareSubmaps(
    const std::vector<SubmapInput>& inputs, const MergeParams& params) {
  MAPD_RETURN_IF_ERROR(params.Validate());
  // With the correlation generator first (the default), every pair levels
  // both maps: their gravity frames are computed here, with the views, one
  // input per thread.
  const bool level_now = params.correlation.enabled && params.correlation.after_corner_stages == 0;
  std::vector<std::shared_ptr<PreparedSubmap>> prepared(inputs.size());
  std::vector<Status> read(inputs.size());
  // Gravity() records its time; here that time is part of reading_s, so the
  // per-input records (one each: the threads must not share one) are dropped.
  std::vector<StageTimes> view_times(inputs.size());
  ParallelFor(inputs.size(), params.threads, [&](std::size_t i, std::size_t) {
    auto parts = std::make_unique<PreparedSubmap::Parts>();
    parts->params = params;
    parts->id = inputs[i].id;
    auto tree = ReadOctree(inputs[i].bytes);
    if (!tree.ok()) {
      read[i] = Status(tree.status().code(), Name(inputs[i].id) + ": " + tree.status().message());
      return;
    }
    auto grid = VoxelGrid::FromOcTree(**tree);
    if (!grid.ok()) {
      read[i] = Status(grid.status().code(), Name(inputs[i].id) + ": " + grid.status().message());
      return;
    }
    parts->tree = std::move(tree).value();
    parts->grid = std::move(grid).value();
    parts->features.emplace(parts->id, &parts->grid, &parts->params);
    if (level_now) parts->features->Gravity(&view_times[i]);  // errors: AlignPair's to report
    prepared[i] = std::make_shared<PreparedSubmap>(std::move(parts));
  });
  for (const Status& status : read) MAPD_RETURN_IF_ERROR(status);
  return prepared;
}

StatusOr<MergeOutcome> MergeSubmaps(const std::vector<SubmapInput>& inputs,
                                    const MergeParams& params,
                                    const ProgressCallback& progress_callback) {
  const Clock::time_point start = Clock::now();
  MAPD_RETURN_IF_ERROR(params.Validate());
  std::vector<uint64_t> ids;
  for (const SubmapInput& input : inputs) ids.push_back(input.id);
  MAPD_RETURN_IF_ERROR(CheckInputIds(ids));
  // Parse (the safe reader) and view every input.
  auto prepared = PrepareSubmaps(inputs, params);
  if (!prepared.ok()) return prepared.status();
  std::vector<PreparedSubmap::Parts*> views;
  for (const auto& submap : *prepared) views.push_back(&submap->parts());
  return MergeViews(views, params, progress_callback, start, SecondsSince(start),
                    /*release=*/true);
}

StatusOr<MergeOutcome> MergePreparedSubmaps(
    const std::vector<std::shared_ptr<PreparedSubmap>>& inputs, const MergeParams& params,
    const ProgressCallback& progress_callback) {
  const Clock::time_point start = Clock::now();
  MAPD_RETURN_IF_ERROR(params.Validate());
  std::vector<uint64_t> ids;
  std::vector<PreparedSubmap::Parts*> views;
  for (const auto& input : inputs) {
    if (input == nullptr) return Status::InvalidArgument("a prepared input is missing");
    ids.push_back(input->id());
    views.push_back(&input->parts());
  }
  MAPD_RETURN_IF_ERROR(CheckInputIds(ids));
  return MergeViews(views, params, progress_callback, start, 0.0, /*release=*/false);
}

namespace {

StatusOr<MergeOutcome> MergeViews(const std::vector<PreparedSubmap::Parts*>& submaps,
                                  const MergeParams& params,
                                  const ProgressCallback& progress_callback,
                                  Clock::time_point start, double reading_s, bool release) {
  const Progress progress(progress_callback);
  MergeOutcome outcome;
  outcome.times.reading_s = reading_s;
  for (PreparedSubmap::Parts* submap : submaps) submap->features->StartMerge();
  Clock::time_point stage_start;
  double finest = submaps[0]->grid.resolution();
  for (const PreparedSubmap::Parts* submap : submaps) {
    const double resolution = submap->grid.resolution();
    if (resolution != submaps[0]->grid.resolution() &&
        params.resolution_policy == ResolutionPolicy::kRefuse) {
      // Named by the service's setting: this is the message an operator sees.
      return Status::FailedPrecondition(
          Name(submaps[0]->id) + " has resolution " + Metres(submaps[0]->grid.resolution()) + ", " +
          Name(submap->id) + " has " + Metres(resolution) +
          "; merge.resolution_policy is refuse (allowed: refuse, resample); set it to resample "
          "to merge them at the finest resolution");
    }
    finest = std::min(finest, resolution);
  }
  outcome.resolution = finest;

  // B.1-B.3: corners of every submap, up front when corner matching runs
  // first: a submap with too few of them fails the merge here. With the
  // correlation generator first (after_corner_stages 0), AlignPair extracts
  // them only for pairs the generator does not settle.
  progress.Report("corners", 0.0);
  const bool corners_first =
      !params.correlation.enabled || params.correlation.after_corner_stages > 0;
  for (std::size_t i = 0; i < submaps.size() && corners_first; ++i) {
    auto corners = submaps[i]->features->Corners(&outcome.times);
    if (!corners.ok()) return corners.status();
    const std::size_t found = (*corners)->size();
    // With the correlation generator, too few corners is for AlignPair to
    // report: corridors and doorways have few corners but walls and floor.
    if (found == 0 && !params.correlation.enabled) {
      return Status::FailedPrecondition("no corners found in " + Name(submaps[i]->id));
    }
    if (static_cast<int>(found) < params.min_matched_corners && !params.correlation.enabled) {
      return Status::FailedPrecondition("only " + std::to_string(found) + " corners found in " +
                                        Name(submaps[i]->id) + ", need " +
                                        std::to_string(params.min_matched_corners));
    }
    progress.Report("corners",
                    0.4 * static_cast<double>(i + 1) / static_cast<double>(submaps.size()));
    MAPD_RETURN_IF_ERROR(OverBudget(start, params, "corner extraction"));
  }
  // B.4-B.5: every pair.
  const std::size_t num_pairs = submaps.size() * (submaps.size() - 1) / 2;
  std::vector<MergeEdge> edges;
  progress.Report("matching", 0.4);
  for (std::size_t i = 0; i < submaps.size(); ++i) {
    for (std::size_t j = i + 1; j < submaps.size(); ++j) {
      const PairSide a{submaps[i]->id, &submaps[i]->grid, &*submaps[i]->features};
      const PairSide b{submaps[j]->id, &submaps[j]->grid, &*submaps[j]->features};
      const double seconds_left = params.max_seconds - SecondsSince(start);
      auto pair = AlignPair(a, b, params, finest, seconds_left, &outcome.times);
      if (!pair.ok()) return pair.status();
      if (pair->accepted) {
        // Matched corners first; the overlap score (< 1) breaks ties.
        edges.push_back({static_cast<int>(i), static_cast<int>(j), pair->T_a_b,
                         pair->matched_corners + pair->overlap_score});
      }
      outcome.pairs.push_back(std::move(pair).value());
      progress.Report("alignment", 0.4 + 0.4 * static_cast<double>(outcome.pairs.size()) /
                                             static_cast<double>(num_pairs));
      MAPD_RETURN_IF_ERROR(OverBudget(start, params, "matching and alignment"));
    }
  }

  for (PreparedSubmap::Parts* submap : submaps) {
    const bool extracted = submap->features->corners_used();
    outcome.corners.push_back(
        extracted ? static_cast<int64_t>((*submap->features->Corners(&outcome.times))->size())
                  : -1);
  }

  // B.7: the maximum spanning tree from the first input.
  const TreePlacement placement =
      PlaceAlongMaximumSpanningTree(static_cast<int>(submaps.size()), edges, 0);
  if (submaps.size() == 2 && !placement.placed[1]) {
    const PairReport& pair = outcome.pairs.front();
    return Status::FailedPrecondition(Name(pair.id_a) + " and " + Name(pair.id_b) +
                                      " not merged: " + pair.reason);
  }
  std::string unplaced;
  for (std::size_t i = 1; i < submaps.size(); ++i) {
    if (placement.placed[i]) continue;
    if (!unplaced.empty()) unplaced += " | ";
    unplaced += Name(submaps[i]->id) + " (" + RefusalsOf(submaps[i]->id, outcome.pairs) + ")";
  }
  if (!unplaced.empty()) {
    return Status::FailedPrecondition("not connected to " + Name(submaps[0]->id) +
                                      " by accepted merges: " + unplaced);
  }
  for (std::size_t i = 0; i < submaps.size(); ++i) {
    Alignment alignment;
    alignment.id = submaps[i]->id;
    alignment.T_reference_submap = placement.T_root_node[i];
    const int parent = placement.parent[i];
    // The evidence of the tree edge that placed it.
    for (const auto& pair : outcome.pairs) {
      if (parent < 0 || !pair.accepted) continue;
      const uint64_t pid = submaps[static_cast<std::size_t>(parent)]->id;
      if ((pair.id_a == pid && pair.id_b == alignment.id) ||
          (pair.id_b == pid && pair.id_a == alignment.id)) {
        alignment.matched_corners = pair.matched_corners;
        alignment.residual_m = pair.residual_m;
        alignment.overlap_score = pair.overlap_score;
        alignment.source = pair.source;
        alignment.by_corners = pair.by_corners;
        alignment.support_fraction = pair.support_fraction;
        alignment.shared_free_ratio = pair.shared_free_ratio;
        alignment.restart_spread_voxels = pair.restart_spread_voxels;
        alignment.second_residual_m = pair.second_residual_m;
        // The parent's corner goes into the reference frame by the parent's placement.
        const Eigen::Isometry3d& T_root_parent =
            placement.T_root_node[static_cast<std::size_t>(parent)];
        const bool parent_is_a = pair.id_a == pid;
        for (const auto& [in_a, in_b] : pair.matched_a_b) {
          MatchedCorner m;
          m.in_submap = parent_is_a ? in_b : in_a;
          m.in_reference = T_root_parent * (parent_is_a ? in_a : in_b);
          alignment.matched.push_back(m);
        }
      }
    }
    outcome.alignments.push_back(alignment);
  }

  // The grids and their features are done with: fusion works on the trees.
  // Freed first, fusion's merged tree and leaf lists reuse their memory (the
  // merge's peak was in fusion, with them still held).
  for (PreparedSubmap::Parts* submap : submaps) {
    if (!release) break;
    submap->features.reset();
    submap->grid = VoxelGrid();
  }

  // B.6: fusion into the first input's frame, breadth-first along the tree.
  stage_start = Clock::now();
  progress.Report("fusion", 0.8);
  FusionParams fusion;
  fusion.rule = params.fusion_rule;
  fusion.max_free_voxels = params.max_fusion_free_voxels;
  fusion.threads = params.threads;
  FusionStats stats;
  auto merged = StartMergedMap(*submaps[0]->tree, finest, fusion, &stats);
  if (!merged.ok()) return merged.status();
  for (std::size_t k = 1; k < placement.order.size(); ++k) {
    const auto i = static_cast<std::size_t>(placement.order[k]);
    MAPD_RETURN_IF_ERROR(
        FuseInto(*submaps[i]->tree, placement.T_root_node[i], fusion, merged->get(), &stats));
    progress.Report(
        "fusion", 0.8 + 0.2 * static_cast<double>(k) / static_cast<double>(placement.order.size()));
    MAPD_RETURN_IF_ERROR(OverBudget(start, params, "fusion"));
  }
  // The file and the count read the tree alone; the inputs are freed
  // meanwhile (a campus pair's trees take ~0.2 s to free).
  StatusOr<std::string> bytes = Status::Internal("not written");
  ParallelFor(2 + submaps.size(), params.threads, [&](std::size_t task, std::size_t) {
    if (task == 0) {
      bytes = WriteBinaryOctree(**merged);
    } else if (task == 1) {
      outcome.occupied_voxels = CountOccupiedVoxels(**merged);
    } else {
      if (release) submaps[task - 2]->tree.reset();
    }
  });
  if (!bytes.ok()) return bytes.status();
  outcome.merged_bt = std::move(bytes).value();
  outcome.merged_tree = std::shared_ptr<void>(std::move(merged).value());
  outcome.free_voxels_skipped = stats.free_voxels_skipped;
  outcome.times.fusion_s = SecondsSince(stage_start);
  outcome.times.total_s = SecondsSince(start);
  progress.Report("fusion", 1.0);
  return outcome;
}

}  // namespace
}  // namespace mapd::voxel
