#include "service/options.h"

#include <string>

namespace mapd::service {

Status IngestLimits::Validate() const {
  if (max_features_per_batch == 0 || max_features_per_batch > kMaxFeaturesPerBatchHard) {
    return Status::InvalidArgument("max_features_per_batch must be in [1, " +
                                   std::to_string(kMaxFeaturesPerBatchHard) + "]");
  }
  if (max_boundary_points < 3) return Status::InvalidArgument("max_boundary_points must be >= 3");
  if (!(max_abs_coordinate_m > 0))
    return Status::InvalidArgument("max_abs_coordinate_m must be > 0");
  if (!(max_feature_length_m > 0))
    return Status::InvalidArgument("max_feature_length_m must be > 0");
  if (!(quaternion_tolerance > 0 && quaternion_tolerance < 0.5)) {
    return Status::InvalidArgument("quaternion_tolerance must be in (0, 0.5)");
  }
  return Status::Ok();
}

}  // namespace mapd::service
