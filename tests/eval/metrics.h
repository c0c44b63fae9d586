// How good a fused map is against the scenario's ground truth (the paper's
// section 4: conciseness, Table 1; accuracy, Table 2).
//
// Matching: a fused segment matches the structure (wall or trivial) whose
// segment is nearest to its midpoint, if its direction is within
// max_angle_rad of the structure's, both its endpoints lie within match_m of
// the structure's line, and its projection overlaps the structure.
#ifndef MAPD_EVAL_METRICS_H_
#define MAPD_EVAL_METRICS_H_

#include <cstddef>
#include <vector>

#include "fusion/engine.h"
#include "sim/city_scenario.h"

namespace mapd::fusion::scenario {

struct MetricsParams {
  double match_m = 0.5;
  double max_angle_rad = 10.0 * 3.14159265358979323846 / 180.0;
  // A wall counts as seen if features of at least this many scans lie on it;
  // a corner is evaluated if both its walls are seen up to within
  // corner_reach_m of it.
  size_t min_scans = 3;
  double corner_reach_m = 0.5;
  // The fused endpoint of a wall "meets" a corner if within this distance.
  double corner_radius_m = 1.0;
};

struct MapMetrics {
  size_t fused = 0;  // Table 1: number of fused features
  size_t walls_seen = 0;
  size_t walls_matched = 0;    // seen walls with at least one matching fused feature
  size_t on_walls = 0;         // fused features matching a wall
  size_t on_trivial = 0;       // fused features matching a fence or pole
  size_t spurious = 0;         // fused features matching no structure
  double redundancy = 0.0;     // on_walls / walls_matched (1 = one feature per wall)
  double completeness = 0.0;   // seen wall length covered by matching fused features
  double lateral_rms_m = 0.0;  // RMS distance of matched fused endpoints to their wall line
  // Table 2: per evaluated corner, the sum over its two walls of the distance
  // from the corner to the nearest endpoint of a fused feature of that wall.
  size_t corners_evaluated = 0;
  size_t corners_met = 0;            // both walls have an endpoint within corner_radius_m
  double vertex_error_mean_m = 0.0;  // over met corners
  double vertex_error_median_m = 0.0;
  std::vector<double> vertex_errors_m;  // per met corner
  std::vector<size_t> met_corners;      // their indices into World::corners, ascending
};

// `raw` is every scan's features with their truth labels (Scan::features/truth).
MapMetrics Evaluate(const World& world, const std::vector<Scan>& raw,
                    const std::vector<FusedFeature>& fused, const MetricsParams& params);

// The structure a segment matches, or -1.
int MatchStructure(const World& world, const geometry::Segment2& s, const MetricsParams& params);

}  // namespace mapd::fusion::scenario

#endif  // MAPD_EVAL_METRICS_H_
