// What an accepted merge does to the frames, and the review of proposed
// merges (ListMerges, GetMerge, ApproveMerge, RejectMerge; the handlers are
// SubmapService's, in merge_review.cc). No voxel library: review works in
// every build, though only a build with it makes proposals.
#ifndef MAPD_SERVICE_MERGE_REVIEW_H_
#define MAPD_SERVICE_MERGE_REVIEW_H_

#include <cstdint>
#include <utility>
#include <vector>

#include "common/status.h"
#include "geometry/merge_frames.h"
#include "geometry/rigid3.h"
#include "mapserver/v1/map_service.pb.h"
#include "service/auth.h"
#include "service/core.h"
#include "storage/store.h"

namespace mapd::service {

using geometry::MergeFrames;
// What an accepted merge implies for the map frame (geometry::FramesOfMerge,
// the rule) with the frames as they are in the store now: the session ties,
// and where each input sits in the map frame (global_map_builder.h).
// T_ref_input[i] maps input i into the reference's (first input's) frame.
// Call on the writer thread.
StatusOr<MergeFrames> FramesOfMerge(storage::Store& store,
                                    const std::vector<storage::SubmapMeta>& inputs,
                                    const std::vector<geometry::Rigid3>& T_ref_input);
// Writes them in the merge's transaction.
Status ApplyMergeFrames(const MergeFrames& frames, int64_t merge_id,
                        storage::WriteTransaction* txn);

// Why `proposal` (with its inputs' `metas`) can no longer be approved
// because of a merge accepted since it was proposed: FailedPrecondition
// naming that merge and the submap or session they share; Ok otherwise.
Status CheckNoLaterConflict(storage::Store& store, const storage::MergeRecord& proposal,
                            const std::vector<storage::SubmapMeta>& metas);

// with_matched: include the inputs' matched corner pairs (GetMerge and the
// decisions; ListMerges leaves them out, see SubmapAlignment.matched).
void ToProto(const storage::MergeRecord& record, bool with_matched,
             mapserver::v1::MergeRecord* out);
// One input of a merge record (the above, and MergeSubmaps' last message).
void ToProto(const storage::MergeInputRecord& in, bool with_matched,
             mapserver::v1::SubmapAlignment* out);

// A decision on proposed merge `id` by `caller` (authorized already):
// approve when `reject_reason` is empty (ties its frames), else reject. On
// the writer thread, audited and logged, a refusal too (NotFound,
// FailedPrecondition naming the state or the conflict). For ApproveMerge,
// RejectMerge and the web view's POSTs.
Status DecideProposal(Core* core, int64_t id, const std::string& reject_reason,
                      const Principal& caller);
// InvalidArgument unless `reason` is a valid rejection reason: 1-1000
// characters, no control characters (see common/text_escape.h).
Status CheckRejectReason(const std::string& reason);

}  // namespace mapd::service

#endif  // MAPD_SERVICE_MERGE_REVIEW_H_
