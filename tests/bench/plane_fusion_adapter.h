// The one place plane_bench meets the fusion of non-vertical planes
// (fusion::PlaneFusionEngine, default PlaneFusionParams): timing and a view
// of the published planes for the coverage figures and the pictures.
#ifndef MAPD_TESTS_BENCH_PLANE_FUSION_ADAPTER_H_
#define MAPD_TESTS_BENCH_PLANE_FUSION_ADAPTER_H_

#include <Eigen/Core>
#include <chrono>
#include <cstdint>
#include <vector>

#include "common/status.h"
#include "fusion/plane_engine.h"
#include "fusion/projection.h"

namespace mapd::bench {

struct FusedPlaneView {
  uint64_t id = 0;
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();
  double offset_m = 0.0;
  std::vector<Eigen::Vector3d> boundary;  // convex, map frame
  double area_m2 = 0.0;
  uint32_t support = 0;
};

struct PlaneFusionResult {
  size_t raw = 0;
  double seconds = 0.0;  // in Add()
  size_t nodes = 0;      // planes the engine keeps as nodes (not folded), at the end
  std::vector<FusedPlaneView> fused;
};

class PlaneFuser {
 public:
  PlaneFuser() : engine_(fusion::PlaneFusionParams{}) {}
  Status Add(uint64_t observation, uint64_t robot, const std::vector<fusion::MapPlane>& planes) {
    result_.raw += planes.size();
    const auto start = std::chrono::steady_clock::now();
    Status s = engine_.Add(observation, robot, planes);
    result_.seconds +=
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return s;
  }
  PlaneFusionResult Result() const {
    PlaneFusionResult r = result_;
    r.nodes = engine_.node_count();
    for (const fusion::FusedPlane& f : engine_.Published()) {
      r.fused.push_back({f.id, f.normal, f.offset_m, f.boundary, f.area_m2, f.support});
    }
    return r;
  }

 private:
  fusion::PlaneFusionEngine engine_;
  PlaneFusionResult result_;
};

}  // namespace mapd::bench

#endif  // MAPD_TESTS_BENCH_PLANE_FUSION_ADAPTER_H_
