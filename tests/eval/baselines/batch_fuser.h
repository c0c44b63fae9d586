// The shared frame of the two competing methods (docs/algorithms.md A.13,
// "Baselines"): both are OFFLINE algorithms, so Add() only files the features
// and the map is computed from all of them when it is asked for. What differs
// between them is the clustering and the merge of a cluster into one segment.
//
// The same post-processing as the proposed method (feature-fusion paper,
// Li et al. 2023, section 4.2: "the same post processing has been employed for all three
// algorithms") is applied to the merged segments: the corner optimisation of
// corner_snap.h with FusionParams::snap_m and corner_mode.
#ifndef MAPD_EVAL_BASELINES_BATCH_FUSER_H_
#define MAPD_EVAL_BASELINES_BATCH_FUSER_H_

#include <cstdint>
#include <map>
#include <unordered_set>
#include <vector>

#include "eval/baselines/mean_shift.h"
#include "eval/fuser.h"
#include "geometry/line_fit.h"

namespace mapd::fusion::baselines {

// Post-processing shared by the baselines.
struct PostParams {
  // A cluster is published if its members come from at least this many distinct
  // observations. The competing methods do not count appearances (the paper
  // names that as one of their weaknesses), so the default 1 publishes all.
  uint32_t min_support = 1;
  double snap_m = 0.5;                                 // as FusionParams::snap_m
  CornerMode corner_mode = CornerMode::kIntersection;  // as FusionParams::corner_mode
};

class BatchFuser : public Fuser {
 public:
  Status Add(ObservationId observation, RobotId robot, const std::vector<GroundFeature>& features,
             ChangeFeed* changes) final;
  std::vector<FusedFeature> Published() const final;

  size_t feature_count() const { return members_.size(); }

 protected:
  struct Member {
    GroundFeature feature;
    ObservationId observation = 0;
    RobotId robot = 0;
  };
  explicit BatchFuser(const PostParams& post) : post_(post) {}

  // A partition of all members (indices into `members`); every member in exactly one cluster.
  virtual std::vector<std::vector<uint32_t>> Cluster(const std::vector<Member>& members) const = 0;
  // The representative line of one cluster; the fused segment is the extent of
  // the members' endpoints projected onto it.
  virtual geometry::Line2 MergeLine(const std::vector<Member>& members,
                                    const std::vector<uint32_t>& cluster) const = 0;

  // Step 1 of both methods: the members grouped by their mode of mean shift on
  // the axial orientation (unweighted), in mode order; indices into `members`.
  static std::vector<std::vector<uint32_t>> OrientationGroups(const std::vector<Member>& members,
                                                              const OrientationShiftParams& params);

 private:
  std::vector<FusedFeature> Compute() const;

  PostParams post_;
  std::vector<Member> members_;
  std::unordered_set<ObservationId> observations_;
  std::unordered_set<FeatureId> feature_ids_;
  mutable bool dirty_ = false;
  mutable std::vector<FusedFeature> cache_;
};

}  // namespace mapd::fusion::baselines

#endif  // MAPD_EVAL_BASELINES_BATCH_FUSER_H_
