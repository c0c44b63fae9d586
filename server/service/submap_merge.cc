// SubmapService::Merge (MergeSubmaps), in named steps; the rules are in
// submap_service.h.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <string>
#include <thread>
#include <unordered_set>
#include <utility>
#include <vector>

#include "common/clock.h"
#include "service/global_map_builder.h"
#include "service/log.h"
#include "service/merge_review.h"
#include "service/merge_runner.h"
#include "service/proto_convert.h"
#include "service/status_mapping.h"
#include "service/submap_service.h"
#include "voxel/merge.h"

namespace mapd::service {
namespace {

namespace pb = mapserver::v1;

}  // namespace

voxel::MergeParams ToMergeParams(const SubmapOptions& o) {
  voxel::MergeParams p;
  p.min_matched_corners = o.min_matched_corners;
  p.max_residual_voxels = o.max_residual_voxels;
  p.min_overlap_score = o.min_overlap_score;
  p.min_shared_free_ratio = o.min_shared_free_ratio;
  p.max_restart_spread_voxels = o.max_restart_spread_voxels;
  p.max_seconds = o.max_merge_seconds;
  p.threads = static_cast<int>(
      o.merge_threads > 0 ? o.merge_threads : std::max(1U, std::thread::hardware_concurrency()));
  p.resolution_policy = o.resample_resolutions ? voxel::ResolutionPolicy::kResampleToFinest
                                               : voxel::ResolutionPolicy::kRefuse;
  p.fusion_rule = o.log_odds_fusion ? voxel::FusionRule::kLogOdds : voxel::FusionRule::kOverlapRule;
  p.correlation.enabled = o.correlation;
  p.correlation.after_corner_stages = o.correlation_after_corner_stages;
  p.correlation.check_corner_solutions = o.correlation_check_accepted;
  p.correlation.max_cells = o.correlation_max_cells;
  p.correlation.plan_view_first_min_cells = o.correlation_plan_view_first_cells;
  p.correlation.looser_stages_after_refusal = o.correlation_looser_stages_after_refusal;
  return p;
}

namespace {

std::string Seconds(double s) {
  char buffer[32];
  std::snprintf(buffer, sizeof(buffer), "%.3f", s);
  return buffer;
}

std::string MergeTarget(int64_t merge_id, const std::vector<uint64_t>& ids) {
  std::string s = "merge " + std::to_string(merge_id) + " of submaps";
  for (uint64_t id : ids) s += " " + std::to_string(id);
  return s;
}

geometry::Rigid3 ToRigid(const Eigen::Isometry3d& iso) {
  geometry::Rigid3 T;
  T.rotation = Eigen::Quaterniond(iso.rotation()).normalized();
  T.translation = iso.translation();
  return T;
}

grpc::Status CheckMergeRequest(const pb::MergeSubmapsRequest& request) {
  if (request.submap_ids_size() < 2)
    return InvalidArgument("submap_ids: give two or more submap ids");
  std::unordered_set<uint64_t> distinct;
  for (uint64_t id : request.submap_ids()) {
    if (id == 0) return InvalidArgument("submap_ids: 0 is not a submap id");
    if (!distinct.insert(id).second)
      return InvalidArgument("submap_ids: " + std::to_string(id) + " is given twice");
  }
  return grpc::Status::OK;
}

// The merge record of an accepted or proposed outcome (alignments in input
// order) and the pose of every input in the reference frame: the decision's,
// converted.
StatusOr<storage::NewMerge> AcceptedMerge(const voxel::MergeOutcome& outcome,
                                          const voxel::MergeDecision& decision,
                                          const std::vector<uint64_t>& ids, const Principal& caller,
                                          std::vector<geometry::Rigid3>* T_ref_input) {
  storage::NewMerge merge;
  merge.record.created_ns = UnixNowNs();
  merge.record.requested_by = caller.name;
  if (decision.verdict == voxel::MergeVerdict::kProposed) {
    merge.record.state = storage::MergeState::kProposed;
  } else {
    merge.record.state = storage::MergeState::kAccepted;
    merge.record.decided_by = caller.name;
    merge.record.decided_ns = merge.record.created_ns;
  }
  T_ref_input->assign(ids.size(), geometry::Rigid3::Identity());
  for (size_t i = 0; i < ids.size(); ++i) {
    const auto it = std::find_if(outcome.alignments.begin(), outcome.alignments.end(),
                                 [&](const voxel::Alignment& a) { return a.id == ids[i]; });
    if (it == outcome.alignments.end()) {
      return Status::Internal("the merge returned no alignment for submap " +
                              std::to_string(ids[i]) + "; nothing was stored");
    }
    (*T_ref_input)[i] = ToRigid(decision.T_ref_input[i]);
    storage::MergeInputRecord in;
    in.submap_id = static_cast<int64_t>(ids[i]);
    in.aligned = true;
    in.T_reference_submap = (*T_ref_input)[i];
    in.matched_corners = it->matched_corners;
    in.residual_m = it->residual_m;
    in.overlap_score = it->overlap_score;
    in.source = it->source;
    in.support_fraction = it->support_fraction;
    in.shared_free_ratio = it->shared_free_ratio;
    in.restart_spread_voxels = it->restart_spread_voxels;
    in.second_residual_m = it->second_residual_m;
    for (const voxel::MatchedCorner& m : it->matched) {
      in.matched.push_back({m.in_submap, m.in_reference});
    }
    merge.record.inputs.push_back(std::move(in));
  }
  StatusOr<voxel::SubmapSummary> merged = voxel::InspectSubmap(outcome.merged_bt);
  if (!merged.ok()) {
    return Status::Internal("the merged map does not validate (" + merged.status().ToString() +
                            "); nothing was stored");
  }
  storage::SubmapMeta& m = merge.merged.meta;
  m.format = storage::SubmapFormat::kOctomapBt;
  m.resolution_m = merged->resolution;
  m.occupied_voxels = merged->occupied_voxels;
  m.free_voxels = merged->free_voxels;
  m.bounds_min = merged->bounds_min;
  m.bounds_max = merged->bounds_max;
  m.created_ns = merge.record.created_ns;
  merge.merged.data = outcome.merged_bt;
  return merge;
}

// The last message of an accepted (or proposed) merge.
pb::MergeProgress ResultMessage(const storage::MergeIds& stored,
                                const storage::MergeRecord& record) {
  pb::MergeProgress last;
  last.set_stage("done");
  last.set_fraction(1.0);
  pb::MergeResult* result = last.mutable_result();
  result->set_merge_id(static_cast<uint64_t>(stored.merge_id));
  result->set_merged_submap_id(static_cast<uint64_t>(stored.merged_submap_id));
  result->set_state(record.state == storage::MergeState::kProposed ? pb::MERGE_STATE_PROPOSED
                                                                   : pb::MERGE_STATE_ACCEPTED);
  for (const storage::MergeInputRecord& in : record.inputs) {
    ToProto(in, /*with_matched=*/false, result->add_alignments());
  }
  return last;
}

}  // namespace

grpc::Status SubmapService::LoadMergeInputs(const pb::MergeSubmapsRequest& request,
                                            MergeInputs* inputs) {
  for (uint64_t id : request.submap_ids()) {
    StatusOr<storage::SubmapMeta> meta = core_->store().GetSubmap(static_cast<int64_t>(id));
    if (!meta.ok()) return ToGrpcStatus(meta.status());
    // A merged map is a product, not an observation: merging it again would
    // count its inputs twice, and a proposal's output would be merged (and
    // could become the global map) without anyone having accepted it.
    if (meta->robot == storage::kMergedRobot) {
      return InvalidArgument("submap_ids: submap " + std::to_string(id) + " (" + meta->name +
                             ") is the output of a merge, not an upload; merge the uploaded "
                             "submaps it came from instead (mapctl merges lists each merge's "
                             "inputs)");
    }
    StatusOr<std::string> data = core_->store().GetSubmapData(static_cast<int64_t>(id));
    if (!data.ok()) return ToGrpcStatus(data.status());
    inputs->metas.push_back(*meta);
    inputs->ids.push_back(id);
    inputs->bytes.push_back(std::move(data).value());
  }
  return grpc::Status::OK;
}

grpc::Status SubmapService::AwaitMerge(grpc::ServerContext* context, MergeJob* job, size_t inputs,
                                       grpc::ServerWriter<pb::MergeProgress>* writer) {
  std::vector<MergeProgressEvent> events;
  bool client_gone = false;
  for (;;) {
    const bool done = job->Wait(std::chrono::milliseconds(50), &events);
    for (const MergeProgressEvent& e : events) {
      pb::MergeProgress progress;
      progress.set_stage(e.stage);
      progress.set_fraction(e.fraction);
      client_gone = client_gone || !writer->Write(progress);
    }
    events.clear();
    if (done) return grpc::Status::OK;
    if (client_gone || context->IsCancelled() || draining_) break;
  }
  job->Abandon();
  Log(LogLevel::kInfo, "merge_abandoned",
      {{"inputs", std::to_string(inputs)}, {"why", draining_ ? "shutdown" : "client cancelled"}});
  if (draining_) {
    return grpc::Status(grpc::StatusCode::UNAVAILABLE,
                        "mapd is shutting down; the merge was abandoned and nothing was stored");
  }
  return grpc::Status(grpc::StatusCode::CANCELLED,
                      "the client cancelled the merge; nothing was stored");
}

grpc::Status SubmapService::RecordRefusedMerge(const std::vector<uint64_t>& ids, const Status& why,
                                               double seconds, const Principal& caller) {
  storage::NewMerge merge;
  merge.record.created_ns = UnixNowNs();
  merge.record.state = storage::MergeState::kRefused;
  merge.record.reason = why.ToString();
  merge.record.requested_by = caller.name;
  for (uint64_t id : ids) {
    storage::MergeInputRecord in;
    in.submap_id = static_cast<int64_t>(id);
    merge.record.inputs.push_back(in);
  }
  int64_t merge_id = 0;
  Status recorded = core_->ExecuteWrite([&](storage::WriteTransaction* txn) {
    StatusOr<storage::MergeIds> r = txn->RecordMerge(merge);
    if (!r.ok()) return r.status();
    merge_id = r->merge_id;
    return txn->AppendAudit(AccessControl::Entry(
        caller, "MergeSubmaps", MergeTarget(r->merge_id, ids), "refused: " + why.ToString()));
  });
  Log(LogLevel::kInfo, "merge_refused",
      {{"merge", std::to_string(merge_id)},
       {"inputs", std::to_string(ids.size())},
       {"reason", why.ToString()},
       {"s", std::to_string(seconds)},
       {"recorded", recorded.ok() ? "yes" : recorded.ToString()}});
  return ToGrpcStatus(Status(why.code(), why.message() + " (merge refused; nothing was merged)"));
}

Status SubmapService::StoreAcceptedMerge(const storage::NewMerge& merge, const MergeInputs& inputs,
                                         const std::vector<geometry::Rigid3>& T_ref_input,
                                         const Principal& caller, storage::MergeIds* stored,
                                         size_t* tied) {
  return core_->ExecuteWrite([&](storage::WriteTransaction* txn) {
    // On the writer thread, so no delete or tie can slip in between these
    // checks and the commit: the inputs still exist, and two merges
    // cannot both tie one session from stale views of the frames.
    for (const storage::SubmapMeta& in : inputs.metas) {
      StatusOr<storage::SubmapMeta> still = core_->store().GetSubmap(in.id);
      if (!still.ok()) {
        return Status::FailedPrecondition("submap " + std::to_string(in.id) +
                                          " was deleted while the merge ran; nothing was stored");
      }
    }
    const bool proposed = merge.record.state == storage::MergeState::kProposed;
    // A proposal ties nothing until it is approved (ApproveMerge).
    StatusOr<MergeFrames> frames = MergeFrames();
    if (!proposed) frames = FramesOfMerge(core_->store(), inputs.metas, T_ref_input);
    if (!frames.ok()) return frames.status();
    StatusOr<storage::MergeIds> r = txn->RecordMerge(merge);
    if (!r.ok()) return r.status();
    *stored = *r;
    MAPD_RETURN_IF_ERROR(txn->AppendAudit(
        AccessControl::Entry(caller, "MergeSubmaps", MergeTarget(r->merge_id, inputs.ids),
                             proposed ? "proposed: waits for ApproveMerge" : "ok")));
    MAPD_RETURN_IF_ERROR(ApplyMergeFrames(*frames, r->merge_id, txn));
    *tied = frames->ties.size();
    return Status::Ok();
  });
}

grpc::Status SubmapService::Merge(grpc::ServerContext* context,
                                  const pb::MergeSubmapsRequest& request,
                                  grpc::ServerWriter<pb::MergeProgress>* writer,
                                  const Principal& caller) {
  if (grpc::Status s = CheckMergeRequest(request); !s.ok()) return s;
  if (draining_) return ShuttingDown();
  MergeInputs inputs;
  if (grpc::Status s = LoadMergeInputs(request, &inputs); !s.ok()) return s;

  const auto t0 = std::chrono::steady_clock::now();
  StatusOr<std::shared_ptr<MergeJob>> job = merges_->Submit(
      prepared_owner_, inputs.ids, std::move(inputs.bytes), ToMergeParams(options_));
  if (!job.ok()) return ToGrpcStatus(job.status());
  if (grpc::Status s = AwaitMerge(context, job->get(), inputs.ids.size(), writer); !s.ok())
    return s;
  const StatusOr<voxel::MergeOutcome> outcome = (*job)->TakeResult();
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (!outcome.ok() && outcome.status().code() == StatusCode::kUnavailable)
    return ToGrpcStatus(outcome.status());  // shutdown: nothing to record
  // The library decides (voxel::DecideMerge, the benchmark's too); this
  // handler converts and stores.
  std::vector<double> resolutions;
  for (const storage::SubmapMeta& m : inputs.metas) resolutions.push_back(m.resolution_m);
  const bool review = request.review() || options_.merge_review;
  const voxel::MergeDecision decision =
      voxel::DecideMerge(outcome, inputs.ids, resolutions, ToMergeParams(options_), review);
  if (decision.verdict == voxel::MergeVerdict::kRefused)
    return RecordRefusedMerge(inputs.ids, decision.reason, seconds, caller);

  std::vector<geometry::Rigid3> T_ref_input;
  StatusOr<storage::NewMerge> merge =
      AcceptedMerge(*outcome, decision, inputs.ids, caller, &T_ref_input);
  if (!merge.ok()) return ToGrpcStatus(merge.status());
  storage::MergeIds stored;
  size_t tied = 0;
  MAPD_RETURN_IF_ERROR_GRPC(
      StoreAcceptedMerge(*merge, inputs, T_ref_input, caller, &stored, &tied));
  if (!review) global_->Invalidate();  // its inputs were placed
  Log(LogLevel::kInfo, review ? "merge_proposed" : "merge_accepted",
      {{"merge", std::to_string(stored.merge_id)},
       {"merged_submap", std::to_string(stored.merged_submap_id)},
       {"inputs", std::to_string(inputs.ids.size())},
       {"sessions_tied", std::to_string(tied)},
       {"s", std::to_string(seconds)},
       // Where the time went (read_s 0: every input was prepared ahead).
       {"read_s", Seconds(outcome->times.reading_s)},
       {"correlation_s", Seconds(outcome->times.correlation_s)},
       {"alignment_s", Seconds(outcome->times.alignment_s)},
       {"fusion_s", Seconds(outcome->times.fusion_s)}});
  writer->Write(
      ResultMessage(stored, merge->record));  // stored either way; a client that left can list it
  return grpc::Status::OK;
}

}  // namespace mapd::service
