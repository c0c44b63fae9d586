// Merge records and their review: SubmapService::ListMerges, GetMerge,
// ApproveMerge, RejectMerge (rules in submap_service.h, "Review").
#include "service/merge_review.h"

#include <string>
#include <unordered_map>
#include <unordered_set>

#include "common/clock.h"
#include "common/text_escape.h"
#include "service/global_map_builder.h"
#include "service/log.h"
#include "service/proto_convert.h"
#include "service/status_mapping.h"
#include "service/submap_service.h"

namespace mapd::service {
namespace {

namespace pb = mapserver::v1;

constexpr size_t kMaxReasonChars = 1000;

std::string MergeName(int64_t id) { return "merge " + std::to_string(id); }

// The inputs of `record` as stored now; FailedPrecondition naming the first
// one (or the merged map) that was deleted.
StatusOr<std::vector<storage::SubmapMeta>> StoredInputs(storage::Store& store,
                                                        const storage::MergeRecord& record) {
  std::vector<storage::SubmapMeta> metas;
  for (const storage::MergeInputRecord& in : record.inputs) {
    StatusOr<storage::SubmapMeta> meta = store.GetSubmap(in.submap_id);
    if (meta.status().code() == StatusCode::kNotFound) {
      return Status::FailedPrecondition(
          "input submap " + std::to_string(in.submap_id) + " of " + MergeName(record.id) +
          " was deleted since it was proposed; reject it, or upload and merge again");
    }
    if (!meta.ok()) return meta.status();
    metas.push_back(*std::move(meta));
  }
  StatusOr<storage::SubmapMeta> merged = store.GetSubmap(record.merged_submap_id);
  if (merged.status().code() == StatusCode::kNotFound) {
    return Status::FailedPrecondition("the merged map of " + MergeName(record.id) + " (submap " +
                                      std::to_string(record.merged_submap_id) +
                                      ") was deleted; reject it, or merge again");
  }
  if (!merged.ok()) return merged.status();
  return metas;
}

}  // namespace

StatusOr<MergeFrames> FramesOfMerge(storage::Store& store,
                                    const std::vector<storage::SubmapMeta>& inputs,
                                    const std::vector<geometry::Rigid3>& T_ref_input) {
  // What the map knows of each input's frame now; the rule is the library's.
  StatusOr<std::vector<storage::SubmapPlacement>> placements = store.ListPlacements();
  if (!placements.ok()) return placements.status();
  std::vector<geometry::MergeInputFrame> frames(inputs.size());
  for (size_t i = 0; i < inputs.size(); ++i) {
    frames[i].submap_id = inputs[i].id;
    frames[i].session_id = inputs[i].session_id;
    if (inputs[i].session_id != 0) {
      StatusOr<storage::SessionFrame> f = store.GetSession(inputs[i].session_id);
      if (!f.ok()) return f.status();
      if (f->tied) frames[i].T_map_session = f->T_map_frame;
      continue;
    }
    for (const storage::SubmapPlacement& p : *placements) {
      if (p.submap_id == inputs[i].id) frames[i].T_map_submap = p.T_map_submap;
    }
  }
  return geometry::FramesOfMerge(frames, T_ref_input);
}

Status ApplyMergeFrames(const MergeFrames& frames, int64_t merge_id,
                        storage::WriteTransaction* txn) {
  for (const auto& [session_id, T_map_frame] : frames.ties)
    MAPD_RETURN_IF_ERROR(txn->TieSession(session_id, T_map_frame));
  for (const auto& [submap_id, T_map_submap] : frames.placements)
    MAPD_RETURN_IF_ERROR(txn->PlaceSubmap(submap_id, merge_id, T_map_submap));
  return Status::Ok();
}

Status CheckNoLaterConflict(storage::Store& store, const storage::MergeRecord& proposal,
                            const std::vector<storage::SubmapMeta>& metas) {
  std::unordered_set<int64_t> submaps;
  std::unordered_map<int64_t, std::string> sessions;  // session id -> robot
  for (const storage::SubmapMeta& m : metas) {
    submaps.insert(m.id);
    if (m.session_id != 0) sessions.emplace(m.session_id, m.robot);
  }
  StatusOr<std::vector<storage::MergeRecord>> all = store.ListMerges();
  if (!all.ok()) return all.status();
  for (const storage::MergeRecord& other : *all) {
    // Accepted after this one was proposed: made later, or approved later.
    const bool since = other.id > proposal.id || other.decided_ns >= proposal.created_ns;
    if (other.id == proposal.id || other.state != storage::MergeState::kAccepted || !since)
      continue;
    const std::string prefix =
        MergeName(other.id) + ", accepted since " + MergeName(proposal.id) + " was proposed, ";
    const std::string advice = "; its frames are fixed now: reject this one and merge again";
    for (const storage::MergeInputRecord& in : other.inputs) {
      std::string shared;
      if (submaps.count(in.submap_id) != 0) {
        shared = "also aligns submap " + std::to_string(in.submap_id);
      } else if (StatusOr<storage::SubmapMeta> meta = store.GetSubmap(in.submap_id);
                 meta.ok() && meta->session_id != 0 && sessions.count(meta->session_id) != 0) {
        // (An accepted merge pins its inputs; a missing one would share nothing.)
        shared = "also places the session frame of robot '" + sessions[meta->session_id] +
                 "' (through submap " + std::to_string(in.submap_id) + ")";
      }
      if (!shared.empty()) {
        std::string why = prefix;
        why += shared;
        why += advice;
        return Status::FailedPrecondition(why);
      }
    }
  }
  return Status::Ok();
}

void ToProto(const storage::MergeInputRecord& in, bool with_matched, pb::SubmapAlignment* a) {
  a->set_submap_id(static_cast<uint64_t>(in.submap_id));
  if (!in.aligned) return;
  ToProto(in.T_reference_submap, a->mutable_t_reference_submap());
  a->set_matched_corners(static_cast<uint32_t>(std::max(0, in.matched_corners)));
  a->set_residual_m(in.residual_m);
  a->set_overlap_score(in.overlap_score);
  a->set_source(in.source);
  a->set_support_fraction(in.support_fraction);
  a->set_shared_free_ratio(in.shared_free_ratio);
  a->set_restart_spread_voxels(in.restart_spread_voxels);
  a->set_second_residual_m(in.second_residual_m);
  if (!with_matched) return;
  for (const storage::MatchedCornerRecord& m : in.matched) {
    pb::MatchedCorner* c = a->add_matched();
    ToProto(m.in_submap, c->mutable_in_submap());
    ToProto(m.in_reference, c->mutable_in_reference());
  }
}

// with_matched: the corner pairs (GetMerge only; see SubmapAlignment.matched).
void ToProto(const storage::MergeRecord& r, bool with_matched, pb::MergeRecord* out) {
  out->set_id(static_cast<uint64_t>(r.id));
  out->set_state(static_cast<pb::MergeState>(static_cast<int>(r.state)));
  for (const storage::MergeInputRecord& in : r.inputs) ToProto(in, with_matched, out->add_inputs());
  out->set_reason(r.reason);
  out->set_merged_submap_id(static_cast<uint64_t>(r.merged_submap_id));
  out->set_requested_by(r.requested_by);
  out->set_created_ns(r.created_ns);
  out->set_decided_by(r.decided_by);
  out->set_decided_ns(r.decided_ns);
}

grpc::Status SubmapService::ListMerges(const pb::ListMergesRequest& request,
                                       pb::ListMergesResponse* response) {
  if (!pb::MergeState_IsValid(request.state()))
    return InvalidArgument("state: " + std::to_string(request.state()) + " is not a MergeState");
  StatusOr<std::vector<storage::MergeRecord>> all = core_->store().ListMerges();
  if (!all.ok()) return ToGrpcStatus(all.status());
  for (const storage::MergeRecord& r : *all) {
    if (request.state() != pb::MERGE_STATE_UNSPECIFIED &&
        static_cast<int>(r.state) != static_cast<int>(request.state()))
      continue;
    ToProto(r, /*with_matched=*/false, response->add_merges());
  }
  return grpc::Status::OK;
}

grpc::Status SubmapService::GetMerge(const pb::GetMergeRequest& request,
                                     pb::MergeRecord* response) {
  if (request.id() == 0) return InvalidArgument("id: required (a merge id, see ListMerges)");
  StatusOr<storage::MergeRecord> r = core_->store().GetMerge(static_cast<int64_t>(request.id()));
  if (!r.ok()) return ToGrpcStatus(r.status());
  ToProto(*r, /*with_matched=*/true, response);
  return grpc::Status::OK;
}

Status DecideProposal(Core* core, int64_t id, const std::string& reject_reason,
                      const Principal& caller) {
  const bool approve = reject_reason.empty();
  const std::string action = approve ? "ApproveMerge" : "RejectMerge";
  size_t tied = 0;
  const Status outcome = core->ExecuteWrite([&](storage::WriteTransaction* txn) -> Status {
    if (!approve) {
      MAPD_RETURN_IF_ERROR(txn->DecideMerge(id, storage::MergeState::kRejected, caller.name,
                                            UnixNowNs(), reject_reason));
      return txn->AppendAudit(
          AccessControl::Entry(caller, action, MergeName(id), "ok: " + reject_reason));
    }
    // On the writer thread: no delete, tie or other decision can come
    // between these checks and the commit.
    storage::Store& store = core->store();
    StatusOr<storage::MergeRecord> merge = store.GetMerge(id);
    if (!merge.ok()) return merge.status();
    if (merge->state != storage::MergeState::kProposed) {
      return Status::FailedPrecondition(MergeName(id) + " is " +
                                        storage::MergeStateName(merge->state) +
                                        "; only a proposed merge can be approved");
    }
    StatusOr<std::vector<storage::SubmapMeta>> metas = StoredInputs(store, *merge);
    if (!metas.ok()) return metas.status();
    MAPD_RETURN_IF_ERROR(CheckNoLaterConflict(store, *merge, *metas));
    std::vector<geometry::Rigid3> T_ref_input;
    for (const storage::MergeInputRecord& in : merge->inputs)
      T_ref_input.push_back(in.T_reference_submap);
    StatusOr<MergeFrames> frames = FramesOfMerge(store, *metas, T_ref_input);
    if (!frames.ok()) return frames.status();
    MAPD_RETURN_IF_ERROR(
        txn->DecideMerge(id, storage::MergeState::kAccepted, caller.name, UnixNowNs(), ""));
    MAPD_RETURN_IF_ERROR(
        txn->AppendAudit(AccessControl::Entry(caller, action, MergeName(id), "ok")));
    MAPD_RETURN_IF_ERROR(ApplyMergeFrames(*frames, id, txn));
    tied = frames->ties.size();
    return Status::Ok();
  });
  const std::string result = outcome.ok() ? "ok" : outcome.ToString();
  if (approve) {
    Log(LogLevel::kInfo, outcome.ok() ? "merge_approved" : "merge_approve_refused",
        {{"merge", std::to_string(id)},
         {"by", caller.name},
         {"sessions_tied", std::to_string(tied)},
         {"result", result}});
  } else {
    Log(LogLevel::kInfo, outcome.ok() ? "merge_rejected" : "merge_reject_refused",
        {{"merge", std::to_string(id)}, {"by", caller.name}, {"result", result}});
  }
  if (!outcome.ok()) {
    // The decision's transaction rolled back with its audit row: the refusal gets its own.
    const Status audited = core->ExecuteWrite([&](storage::WriteTransaction* txn) {
      return txn->AppendAudit(
          AccessControl::Entry(caller, action, MergeName(id), outcome.ToString()));
    });
    if (!audited.ok())
      Log(LogLevel::kWarn, "audit_failed", {{"action", action}, {"error", audited.ToString()}});
  }
  return outcome;
}

Status CheckRejectReason(const std::string& reason) {
  if (reason.empty())
    return Status::InvalidArgument("reason: required (why the merge is rejected, for the record)");
  if (reason.size() > kMaxReasonChars) {
    return Status::InvalidArgument("reason: " + std::to_string(reason.size()) +
                                   " characters, at most " + std::to_string(kMaxReasonChars));
  }
  // One line of text: the reason is shown in `mapctl merges`, the audit log
  // and the web view, where a newline or an ESC would forge rows.
  if (const std::string shown = EscapeControlChars(reason); shown != reason) {
    return Status::InvalidArgument("reason: control characters are not allowed (got '" +
                                   shown.substr(0, 80) + "'); write it on one line");
  }
  return Status::Ok();
}

grpc::Status SubmapService::FinishDecision(int64_t id, const Status& outcome,
                                           pb::MergeRecord* response) {
  if (!outcome.ok()) return ToGrpcStatus(outcome);
  StatusOr<storage::MergeRecord> r = core_->store().GetMerge(id);
  if (!r.ok()) return ToGrpcStatus(r.status());
  ToProto(*r, /*with_matched=*/true, response);
  return grpc::Status::OK;
}

grpc::Status SubmapService::ApproveMerge(const pb::ApproveMergeRequest& request,
                                         const Principal& caller, pb::MergeRecord* response) {
  if (request.id() == 0) return InvalidArgument("id: required (a merge id, see ListMerges)");
  if (draining_) return ShuttingDown();
  const auto id = static_cast<int64_t>(request.id());
  const Status decided = DecideProposal(core_, id, "", caller);
  if (decided.ok()) global_->Invalidate();  // its inputs were placed
  return FinishDecision(id, decided, response);
}

grpc::Status SubmapService::RejectMerge(const pb::RejectMergeRequest& request,
                                        const Principal& caller, pb::MergeRecord* response) {
  if (request.id() == 0) return InvalidArgument("id: required (a merge id, see ListMerges)");
  if (Status s = CheckRejectReason(request.reason()); !s.ok()) return ToGrpcStatus(s);
  if (draining_) return ShuttingDown();
  const auto id = static_cast<int64_t>(request.id());
  return FinishDecision(id, DecideProposal(core_, id, request.reason(), caller), response);
}

}  // namespace mapd::service
