#include "fusion/params.h"

#include <cmath>
#include <cstdio>

#include "common/param_check.h"

namespace mapd::fusion {

Status FusionParams::Validate() const {
  // The included angle beta lies in [0, pi/2], so delta above pi/2 means nothing.
  MAPD_RETURN_IF_ERROR(CheckParamRange("fusion params", "delta_rad", delta_rad, 0.0, M_PI_2));
  // gamma = 0 is allowed: the engine's candidate search relies on criterion 3
  // (D <= min(R_f, R_g) + eta), not on criterion 2, so it stays exact.
  MAPD_RETURN_IF_ERROR(CheckParamRange("fusion params", "gamma", gamma, 0.0, 1.0));
  MAPD_RETURN_IF_ERROR(CheckParamRange("fusion params", "eta_m", eta_m, 0.0, HUGE_VAL));
  MAPD_RETURN_IF_ERROR(CheckParamRange("fusion params", "snap_m", snap_m, 0.0, HUGE_VAL));
  MAPD_RETURN_IF_ERROR(
      CheckParamRange("fusion params", "max_plane_tilt_rad", max_plane_tilt_rad, 0.0, M_PI_2));
  MAPD_RETURN_IF_ERROR(
      CheckParamRange("fusion params", "chain_max_rms_m", chain_max_rms_m, 0.0, HUGE_VAL));
  MAPD_RETURN_IF_ERROR(CheckParamRange("fusion params", "cover_m", cover_m, 0.0, HUGE_VAL));
  if (mode != FusionMode::kExact && mode != FusionMode::kBounded) {
    return Status::InvalidArgument("fusion params: mode is not a known mode");
  }
  MAPD_RETURN_IF_ERROR(
      CheckParamRange("fusion params", "chain_max_sse_ratio", chain_max_sse_ratio, 0.0, 1.0));
  MAPD_RETURN_IF_ERROR(CheckParamRange("fusion params", "wall_gap_m", wall_gap_m, 0.0, HUGE_VAL));
  MAPD_RETURN_IF_ERROR(
      CheckParamRange("fusion params", "wall_offset_m", wall_offset_m, 0.0, HUGE_VAL));
  MAPD_RETURN_IF_ERROR(
      CheckParamRange("fusion params", "wall_occluded_gap_m", wall_occluded_gap_m, 0.0, HUGE_VAL));
  MAPD_RETURN_IF_ERROR(CheckParamRange("fusion params", "wall_occluded_gap_ratio",
                                       wall_occluded_gap_ratio, 0.0, 1000.0));
  MAPD_RETURN_IF_ERROR(
      CheckParamRange("fusion params", "wall_proof_gap_m", wall_proof_gap_m, 0.0, 1000.0));
  if (wall_occluded_gap_ratio == 0.0) {
    return Status::InvalidArgument("fusion params: wall_occluded_gap_ratio must be > 0");
  }
  if (wall_free_min_count < 1 || wall_free_min_count > 255) {
    return Status::InvalidArgument("fusion params: wall_free_min_count must be in [1, 255]");
  }
  if (retire_views > 255) {
    return Status::InvalidArgument("fusion params: retire_views must be in [0, 255]");
  }
  MAPD_RETURN_IF_ERROR(
      CheckParamRange("fusion params", "retire_fraction", retire_fraction, 0.0, 1.0));
  MAPD_RETURN_IF_ERROR(
      CheckParamRange("fusion params", "refit_tolerance_m", refit_tolerance_m, 0.0, 0.05));
  if (retire_fraction == 0.0) {
    return Status::InvalidArgument("fusion params: retire_fraction must be > 0");
  }
  if (max_component_nodes < 16 || max_component_nodes > (1u << 20)) {
    return Status::InvalidArgument("fusion params: max_component_nodes must be in [16, 1048576]");
  }
  if (max_link_candidates < 16 || max_link_candidates > (1u << 20)) {
    return Status::InvalidArgument("fusion params: max_link_candidates must be in [16, 1048576]");
  }
  if (max_wall_pieces < 16 || max_wall_pieces > (1u << 20)) {
    return Status::InvalidArgument("fusion params: max_wall_pieces must be in [16, 1048576]");
  }
  MAPD_RETURN_IF_ERROR(
      CheckParamRange("fusion params", "evidence_range_m", evidence_range_m, 0.0, 1000.0));
  MAPD_RETURN_IF_ERROR(
      CheckParamRange("fusion params", "max_wall_length_m", max_wall_length_m, 1.0, 1e6));
  if (evidence_range_m == 0.0) {
    return Status::InvalidArgument("fusion params: evidence_range_m must be > 0");
  }
  if (min_support == 0) {
    return Status::InvalidArgument("fusion params: min_support must be at least 1");
  }
  if (corner_mode != CornerMode::kMidpoint && corner_mode != CornerMode::kIntersection) {
    return Status::InvalidArgument("fusion params: corner_mode is not a known mode");
  }
  if (corner_pairing != CornerPairing::kMutualNearest && corner_pairing != CornerPairing::kGreedy) {
    return Status::InvalidArgument("fusion params: corner_pairing is not a known pairing");
  }
  return Status::Ok();
}

std::string FusionParamsKey(const FusionParams& p) {
  char text[1024];
  std::snprintf(text, sizeof(text),
                "mode=%s cover_m=%.17g delta_rad=%.17g gamma=%.17g eta_m=%.17g min_support=%u "
                "snap_m=%.17g corner_mode=%s corner_pairing=%s max_plane_tilt_rad=%.17g "
                "chain_max_rms_m=%.17g chain_max_sse_ratio=%.17g consolidate=%d wall_gap_m=%.17g "
                "wall_offset_m=%.17g",
                FusionModeName(p.mode), p.cover_m, p.delta_rad, p.gamma, p.eta_m, p.min_support,
                p.snap_m, CornerModeName(p.corner_mode), CornerPairingName(p.corner_pairing),
                p.max_plane_tilt_rad, p.chain_max_rms_m, p.chain_max_sse_ratio,
                p.consolidate ? 1 : 0, p.wall_gap_m, p.wall_offset_m);
  std::string key = text;
  // Appended only when on, so that snapshots taken without it stay loadable.
  if (p.wall_occluded_gap_m > 0.0) {
    std::snprintf(text, sizeof(text),
                  " wall_occluded_gap_m=%.17g wall_occluded_gap_ratio=%.17g wall_free_min_count=%u"
                  " evidence_model=2 wall_proof_gap_m=%.17g evidence_range_m=%.17g",
                  p.wall_occluded_gap_m, p.wall_occluded_gap_ratio, p.wall_free_min_count,
                  p.wall_proof_gap_m, p.evidence_range_m);
    key += text;
    if (p.retire_views > 0 && p.consolidate) {
      std::snprintf(text, sizeof(text), " retire_views=%u retire_fraction=%.17g", p.retire_views,
                    p.retire_fraction);
      key += text;
    }
  }
  // Bounded mode only (exact mode makes every link); changes results only
  // on maps with a component past the cap.
  if (p.mode == FusionMode::kBounded) {
    std::snprintf(text, sizeof(text),
                  " max_component_nodes=%u max_link_candidates=%u max_wall_length_m=%.17g"
                  " max_wall_pieces=%u",
                  p.max_component_nodes, p.max_link_candidates, p.max_wall_length_m,
                  p.max_wall_pieces);
    key += text;
    // Appended only when on, so that snapshots taken without it stay loadable.
    if (p.refit_tolerance_m > 0.0) {
      std::snprintf(text, sizeof(text), " refit_tolerance_m=%.17g", p.refit_tolerance_m);
      key += text;
    }
  }
  return key;
}

const char* FusionModeName(FusionMode mode) {
  switch (mode) {
    case FusionMode::kExact:
      return "exact";
    case FusionMode::kBounded:
      return "bounded";
  }
  return "unknown";
}

Status ParseFusionMode(const std::string& name, FusionMode* mode) {
  if (name == "exact") {
    *mode = FusionMode::kExact;
  } else if (name == "bounded") {
    *mode = FusionMode::kBounded;
  } else {
    return Status::InvalidArgument("fusion.mode \"" + name +
                                   "\" is unknown; expected \"exact\" or \"bounded\"");
  }
  return Status::Ok();
}

const char* CornerModeName(CornerMode mode) {
  switch (mode) {
    case CornerMode::kMidpoint:
      return "midpoint";
    case CornerMode::kIntersection:
      return "intersection";
  }
  return "unknown";
}

Status ParseCornerMode(const std::string& name, CornerMode* mode) {
  if (name == "midpoint") {
    *mode = CornerMode::kMidpoint;
  } else if (name == "intersection") {
    *mode = CornerMode::kIntersection;
  } else {
    return Status::InvalidArgument("corner_mode \"" + name +
                                   "\" is unknown; expected \"midpoint\" or \"intersection\"");
  }
  return Status::Ok();
}

const char* CornerPairingName(CornerPairing pairing) {
  switch (pairing) {
    case CornerPairing::kMutualNearest:
      return "mutual";
    case CornerPairing::kGreedy:
      return "greedy";
  }
  return "unknown";
}

Status ParseCornerPairing(const std::string& name, CornerPairing* pairing) {
  if (name == "mutual") {
    *pairing = CornerPairing::kMutualNearest;
  } else if (name == "greedy") {
    *pairing = CornerPairing::kGreedy;
  } else {
    return Status::InvalidArgument("corner_pairing \"" + name +
                                   "\" is unknown; expected \"mutual\" or \"greedy\"");
  }
  return Status::Ok();
}

}  // namespace mapd::fusion
