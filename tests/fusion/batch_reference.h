// A plain batch implementation of docs/algorithms.md part A, written for
// obviousness, not speed: all pairs, BFS components, the scatter matrix built
// from the member endpoints, every endpoint projected, the corner rule of
// fusion/corner_snap.h evaluated by brute force. The criteria themselves are the
// library's (fusion/criteria.h), which criteria_test.cc checks by hand.
#ifndef MAPD_TESTS_FUSION_BATCH_REFERENCE_H_
#define MAPD_TESTS_FUSION_BATCH_REFERENCE_H_

#include <vector>

#include "fusion/engine.h"
#include "fusion/params.h"

namespace mapd::fusion::testing {

struct BatchObservation {
  ObservationId id = 0;
  RobotId robot = 0;
  std::vector<GroundFeature> features;
};

struct BatchCluster {
  std::vector<FeatureId> members;  // ascending
  ClusterId id = 0;                // members.front()
  geometry::Segment2 fitted;
  geometry::Segment2 segment;  // walls: corner-optimised; clusters: == fitted
  uint32_t support = 0;
  bool published = false;  // clusters: support >= min_support
};

struct BatchResult {
  std::vector<BatchCluster> clusters;  // the guard's groups, ascending id
  // What is published: the published clusters consolidated into walls
  // (one each with consolidation off), ascending id.
  std::vector<BatchCluster> walls;
};

BatchResult BatchFuse(const std::vector<BatchObservation>& observations,
                      const FusionParams& params);

}  // namespace mapd::fusion::testing

#endif  // MAPD_TESTS_FUSION_BATCH_REFERENCE_H_
