#include "geometry/merge_frames.h"

#include <string>
#include <unordered_set>

namespace mapd::geometry {

StatusOr<MergeFrames> FramesOfMerge(const std::vector<MergeInputFrame>& inputs,
                                    const std::vector<Rigid3>& T_ref_input) {
  if (inputs.empty() || inputs.size() != T_ref_input.size()) {
    return Status::InvalidArgument("a merge's frames need one transform per input (" +
                                   std::to_string(inputs.size()) + " inputs, " +
                                   std::to_string(T_ref_input.size()) + " transforms)");
  }
  // 1. The first input with a known pose fixes the reference.
  const auto known_pose = [](const MergeInputFrame& in) -> std::optional<Rigid3> {
    if (in.session_id != 0) return in.T_map_session;
    return in.T_map_submap;
  };
  Rigid3 T_map_ref = Rigid3::Identity();
  for (size_t k = 0; k < inputs.size(); ++k) {
    if (const std::optional<Rigid3> T_map_k = known_pose(inputs[k])) {
      T_map_ref = *T_map_k * T_ref_input[k].inverse();
      break;
    }
  }
  // 2. and 3.
  MergeFrames out;
  std::unordered_set<int64_t> seen;
  for (size_t i = 0; i < inputs.size(); ++i) {
    const Rigid3 T_map_input = T_map_ref * T_ref_input[i];
    out.placements.emplace_back(inputs[i].submap_id, T_map_input);
    const MergeInputFrame& in = inputs[i];
    if (in.session_id == 0 || in.T_map_session || !seen.insert(in.session_id).second) continue;
    out.ties.emplace_back(in.session_id, T_map_input);
  }
  return out;
}

}  // namespace mapd::geometry
