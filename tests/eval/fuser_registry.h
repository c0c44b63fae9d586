// Fusion strategies by name (docs/algorithms.md A.13, "Baselines"):
//   "three_criteria"  the proposed method (FusionEngine, fusion/engine.h)
//   "mean_shift"      competing algorithm 1 (eval/baselines/mean_shift_fuser.h)
//   "density"         competing algorithm 2 (eval/baselines/density_fuser.h)
#ifndef MAPD_EVAL_FUSER_REGISTRY_H_
#define MAPD_EVAL_FUSER_REGISTRY_H_

#include <memory>
#include <string>
#include <vector>

#include "common/status.h"
#include "eval/baselines/density_fuser.h"
#include "eval/baselines/mean_shift_fuser.h"
#include "eval/fuser.h"
#include "fusion/params.h"

namespace mapd::fusion {

// The paper's method is the exact engine: the comparisons with the paper's
// baselines run it. (mapd serves the bounded engine; fusion/params.h.)
inline FusionParams PaperParams() {
  FusionParams p;
  p.mode = FusionMode::kExact;
  return p;
}

struct FuserOptions {
  FusionParams three_criteria = PaperParams();
  baselines::MeanShiftFuserParams mean_shift;
  baselines::DensityFuserParams density;
};

// The registry names, in the order above.
std::vector<std::string> FuserNames();

// InvalidArgument for an unknown name (listing the known ones) or invalid parameters.
StatusOr<std::unique_ptr<Fuser>> MakeFuser(const std::string& name, const FuserOptions& options);

}  // namespace mapd::fusion

#endif  // MAPD_EVAL_FUSER_REGISTRY_H_
