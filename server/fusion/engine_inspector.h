// Test-only view into FusionEngine: the raw cluster partition, which the public
// API does not expose (it names clusters, it does not list their members).
#ifndef MAPD_FUSION_ENGINE_INSPECTOR_H_
#define MAPD_FUSION_ENGINE_INSPECTOR_H_

#include <vector>

#include "fusion/engine.h"

namespace mapd::fusion {

class EngineInspector {
 public:
  // Every cluster as its ascending member ids; clusters ascending by first id.
  static std::vector<std::vector<FeatureId>> Partition(const FusionEngine& engine);
};

}  // namespace mapd::fusion

#endif  // MAPD_FUSION_ENGINE_INSPECTOR_H_
