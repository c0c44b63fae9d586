// Range checks for the validated parameter structs (FusionParams,
// PlaneFusionParams, LidarParams, ...): one wording for every bad value, so an
// operator reads the same "<what>: <field> = <value> is outside [lo, hi]".
#ifndef MAPD_COMMON_PARAM_CHECK_H_
#define MAPD_COMMON_PARAM_CHECK_H_

#include <cmath>
#include <string>

#include "common/status.h"

namespace mapd {

// InvalidArgument naming `what` (the struct, e.g. "fusion params") and `field`
// unless value is finite and lo <= value <= hi.
inline Status CheckParamRange(const char* what, const char* field, double value, double lo,
                              double hi) {
  if (!std::isfinite(value)) {
    return Status::InvalidArgument(std::string(what) + ": " + field + " must be finite");
  }
  if (value < lo || value > hi) {
    return Status::InvalidArgument(std::string(what) + ": " + field + " = " +
                                   std::to_string(value) + " is outside [" + std::to_string(lo) +
                                   ", " + std::to_string(hi) + "]");
  }
  return Status::Ok();
}

}  // namespace mapd

#endif  // MAPD_COMMON_PARAM_CHECK_H_
