// A plain batch implementation of docs/algorithms.md part A, written for
// obviousness, not speed: all pairs, BFS components, the scatter matrix built
// from the member endpoints, every endpoint projected, the corner rule of
// fusion/corner_snap.h evaluated by brute force. The criteria themselves are the
// library's (fusion/criteria.h), which criteria_test.cc checks by hand, and so
// is consolidation's relation without evidence (OnOneWall with no grid,
// wall_consolidation_test.cc). Free-space evidence (A.11) is modelled here from
// the documented rule: every visibility triangle tested against every cell
// centre of its bounding box, and the occluded-gap join and piercing written
// out, with no call into fusion/free_space.h.
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
  // Where the sensor was (FusionEngine::AddFrom): the triangle (sensor, a, b)
  // of every feature was seen through. Without it the observation gives no
  // free-space evidence (FusionEngine::Add).
  bool has_sensor = false;
  geometry::Vec2 sensor_xy_m = geometry::Vec2::Zero();
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
  // What free-space evidence decided, over all pairs of published clusters
  // (zero when it is off: no sensor origin, consolidate off or
  // wall_occluded_gap_m = 0), so that a test can show the evidence mattered.
  struct Evidence {
    bool on = false;
    size_t free_cells = 0;        // cells seen free (>= wall_free_min_count triangles)
    size_t pierced = 0;           // published clusters pierced by a seen-free cell
    size_t occluded_joins = 0;    // pairs joined across an unseen gap > wall_gap_m
    size_t seen_free_vetoes = 0;  // pairs a seen-free cell on the gap kept apart
  } evidence;
};

BatchResult BatchFuse(const std::vector<BatchObservation>& observations,
                      const FusionParams& params);

}  // namespace mapd::fusion::testing

#endif  // MAPD_TESTS_FUSION_BATCH_REFERENCE_H_
