// What an accepted merge does to the map frame (service/submap_service.h,
// "Frames"; docs/algorithms.md A.10): the rule, on plain values. The service
// reads the frames from the store and writes the result in the merge's
// transaction; the rule itself is here, so the service and the review
// (ApproveMerge) apply one rule.
//
//   1. The reference (the first input) sits in the map frame where the first
//      input with a known pose puts it: an input whose session is tied
//      (T_map_session), or one uploaded without a session that an earlier
//      merge placed (T_map_submap). With none known, the reference frame is
//      the map frame (an island: its inputs land at the map origin).
//   2. Every input is placed: T_map_submap = T_map_ref * T_ref_input.
//   3. Every untied session among the inputs is tied, once, by its first
//      input: T_map_session = T_map_ref * T_ref_input (a session's submaps
//      are built in its frame).
#ifndef MAPD_GEOMETRY_MERGE_FRAMES_H_
#define MAPD_GEOMETRY_MERGE_FRAMES_H_

#include <cstdint>
#include <optional>
#include <utility>
#include <vector>

#include "common/status.h"
#include "geometry/rigid3.h"

namespace mapd::geometry {

// One input of a merge and what the map knows of its frame now.
struct MergeInputFrame {
  int64_t submap_id = 0;
  int64_t session_id = 0;               // 0: uploaded without a session
  std::optional<Rigid3> T_map_session;  // the session's tie, when tied
  std::optional<Rigid3> T_map_submap;   // an earlier placement (session 0 only)
};

struct MergeFrames {
  std::vector<std::pair<int64_t, Rigid3>> ties;        // session id, T_map_session
  std::vector<std::pair<int64_t, Rigid3>> placements;  // submap id, T_map_submap
};

// T_ref_input[i] maps input i into the reference's (input 0's) frame.
// InvalidArgument when the two lists differ in length or are empty.
StatusOr<MergeFrames> FramesOfMerge(const std::vector<MergeInputFrame>& inputs,
                                    const std::vector<Rigid3>& T_ref_input);

}  // namespace mapd::geometry

#endif  // MAPD_GEOMETRY_MERGE_FRAMES_H_
