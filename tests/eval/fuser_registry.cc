#include "eval/fuser_registry.h"

#include <cmath>

namespace mapd::fusion {

namespace {

Status ValidateOrientation(const baselines::OrientationShiftParams& p, const std::string& who) {
  if (!(p.bandwidth_rad > 0.0) || !std::isfinite(p.bandwidth_rad)) {
    return Status::InvalidArgument(who + ".orientation.bandwidth_rad must be > 0");
  }
  if (!(p.bin_rad > 0.0) || !(p.bin_rad <= p.bandwidth_rad)) {
    return Status::InvalidArgument(who + ".orientation.bin_rad must be in (0, bandwidth_rad]");
  }
  return Status::Ok();
}

Status ValidatePost(const baselines::PostParams& p, const std::string& who) {
  if (!(p.snap_m >= 0.0) || !std::isfinite(p.snap_m)) {
    return Status::InvalidArgument(who + ".post.snap_m must be >= 0");
  }
  return Status::Ok();
}

}  // namespace

std::vector<std::string> FuserNames() { return {"three_criteria", "mean_shift", "density"}; }

StatusOr<std::unique_ptr<Fuser>> MakeFuser(const std::string& name, const FuserOptions& options) {
  if (name == "three_criteria") {
    MAPD_RETURN_IF_ERROR(options.three_criteria.Validate());
    return std::unique_ptr<Fuser>(std::make_unique<EngineFuser>(options.three_criteria));
  }
  if (name == "mean_shift") {
    const baselines::MeanShiftFuserParams& p = options.mean_shift;
    MAPD_RETURN_IF_ERROR(ValidateOrientation(p.orientation, name));
    MAPD_RETURN_IF_ERROR(ValidatePost(p.post, name));
    if (!(p.centre.bandwidth_m > 0.0) || !std::isfinite(p.centre.bandwidth_m)) {
      return Status::InvalidArgument("mean_shift.centre.bandwidth_m must be > 0");
    }
    return std::unique_ptr<Fuser>(std::make_unique<baselines::MeanShiftFuser>(p));
  }
  if (name == "density") {
    const baselines::DensityFuserParams& p = options.density;
    MAPD_RETURN_IF_ERROR(ValidateOrientation(p.orientation, name));
    MAPD_RETURN_IF_ERROR(ValidatePost(p.post, name));
    if (!(p.lateral_m >= 0.0) || !std::isfinite(p.lateral_m) || !std::isfinite(p.min_overlap_m)) {
      return Status::InvalidArgument("density.lateral_m must be >= 0, min_overlap_m finite");
    }
    if (p.min_pts < 1) return Status::InvalidArgument("density.min_pts must be >= 1");
    return std::unique_ptr<Fuser>(std::make_unique<baselines::DensityFuser>(p));
  }
  std::string known;
  for (const std::string& n : FuserNames()) known += (known.empty() ? "" : ", ") + n;
  return Status::InvalidArgument("unknown fusion strategy \"" + name + "\" (known: " + known + ")");
}

}  // namespace mapd::fusion
