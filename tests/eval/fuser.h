// A common interface for feature-fusion strategies (docs/algorithms.md A.13,
// "Baselines"): the proposed three-criteria engine and the two competing
// methods of the paper, so that the benchmark and the tests can run them side
// by side. Strategies are chosen by name through fuser_registry.h.
//
// Thread safety: none; the caller serialises all calls.
#ifndef MAPD_EVAL_FUSER_H_
#define MAPD_EVAL_FUSER_H_

#include <memory>
#include <vector>

#include "common/status.h"
#include "fusion/engine.h"
#include "fusion/params.h"

namespace mapd::fusion {

class Fuser {
 public:
  virtual ~Fuser() = default;

  // Adds all features of one observation (map frame, ground plane). All-or-nothing:
  // a non-finite or zero-length segment, or a reused FeatureId or ObservationId,
  // is refused with InvalidArgument and the fuser is unchanged. `changes`, if not
  // null, receives what changed in the published map (batch strategies recompute
  // the whole map to fill it: pass null when only the final map matters).
  virtual Status Add(ObservationId observation, RobotId robot,
                     const std::vector<GroundFeature>& features, ChangeFeed* changes) = 0;

  // As Add, for an observation taken from sensor_xy_m (map frame). Strategies
  // that use no free-space evidence ignore the origin.
  virtual Status AddFrom(ObservationId observation, RobotId robot,
                         const geometry::Vec2& /*sensor_xy_m*/,
                         const std::vector<GroundFeature>& features, ChangeFeed* changes) {
    return Add(observation, robot, features, changes);
  }

  // The published fused features, ascending by id (the smallest member FeatureId).
  virtual std::vector<FusedFeature> Published() const = 0;

  // The registry name of the strategy, e.g. "three_criteria".
  virtual const char* name() const = 0;
};

// The proposed method: FusionEngine behind the Fuser interface. (An adapter, not
// a base class of FusionEngine: engine.h defines the feature types this
// interface uses, so FusionEngine cannot derive from it without moving them.)
class EngineFuser : public Fuser {
 public:
  // REQUIRES: params.Validate().ok().
  explicit EngineFuser(const FusionParams& params) : engine_(params) {}

  Status Add(ObservationId observation, RobotId robot, const std::vector<GroundFeature>& features,
             ChangeFeed* changes) override {
    return engine_.Add(observation, robot, features, changes);
  }
  Status AddFrom(ObservationId observation, RobotId robot, const geometry::Vec2& sensor_xy_m,
                 const std::vector<GroundFeature>& features, ChangeFeed* changes) override {
    return engine_.AddFrom(observation, robot, sensor_xy_m, features, changes);
  }
  std::vector<FusedFeature> Published() const override { return engine_.Published(); }
  const char* name() const override { return "three_criteria"; }

  const FusionEngine& engine() const { return engine_; }

 private:
  FusionEngine engine_;
};

}  // namespace mapd::fusion

#endif  // MAPD_EVAL_FUSER_H_
