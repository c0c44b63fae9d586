#include "service/map_service.h"

#include <algorithm>
#include <chrono>
#include <cmath>

#include "service/log.h"
#include "service/proto_convert.h"
#include "service/refused_stream.h"
#include "service/status_mapping.h"
#include "service/watch_service.h"

namespace mapd::service {
namespace {

// An Ingest stream refused at once (the map is still being recovered, or a
// stream limit): the robot reconnects and resends, as after any UNAVAILABLE.
using RefusedIngest = RefusedStream<grpc::ServerBidiReactor<grpc::ByteBuffer, grpc::ByteBuffer>>;

namespace pb = mapserver::v1;

constexpr int kFeaturesPerPage = 4096;
const char* const kVersion = MAPD_VERSION;

Status ParseFeatureMapRequest(const pb::FeatureMapRequest& in, FeatureQuery* out) {
  if (in.has_bbox()) {
    geometry::Box2 box;
    MAPD_RETURN_IF_ERROR(FromProto(in.bbox(), &box));
    out->bbox = box;
  }
  out->min_support = in.min_support();
  MAPD_RETURN_IF_ERROR(FromProto(in.kind(), &out->kind));
  return Status::Ok();
}

template <class Options>
Options WithMap(Options options, const std::string& map_id) {
  options.map_id = map_id;
  return options;
}

}  // namespace

MapServiceImpl::MapServiceImpl(Core* core, IngestOptions ingest_options,
                               const SubmapOptions& submap_options,
                               const StreamLimits& stream_limits, AuthOptions auth_options,
                               MapPlacement placement)
    : core_(core),
      ingest_options_(WithMap(std::move(ingest_options), placement.map_id)),
      stream_limits_(stream_limits),
      own_limiter_(placement.shared_with ? nullptr
                                         : std::make_unique<StreamLimiter>(stream_limits)),
      limiter_(placement.shared_with ? placement.shared_with->limiter_ : own_limiter_.get()),
      own_access_(placement.shared_with ? nullptr
                                        : std::make_unique<AccessControl>(core, auth_options)),
      access_(placement.shared_with ? placement.shared_with->access_ : own_access_.get()),
      submaps_(core, WithMap(submap_options, placement.map_id), access_,
               placement.shared_with ? placement.shared_with->submaps_.merge_runner() : nullptr),
      auth_(core, access_) {}

StatusOr<Principal> MapServiceImpl::AuthenticateToMap(const grpc::ServerContextBase& context,
                                                      const std::string& action) {
  StatusOr<Principal> p = access_->Authenticate(context);
  if (!p.ok()) return p;
  MAPD_RETURN_IF_ERROR(access_->CheckMap(*p, map_id(), action));
  return p;
}

StatusOr<Principal> MapServiceImpl::AdmitToMap(const grpc::ServerContextBase& context,
                                               Permission permission, const std::string& action,
                                               const std::string& robot,
                                               const std::string& target) {
  StatusOr<Principal> p = access_->Admit(context, permission, action, robot, target);
  if (!p.ok()) return p;
  MAPD_RETURN_IF_ERROR(access_->CheckMap(*p, map_id(), action));
  return p;
}

void MapServiceImpl::Tick() {
  submaps_.ExpireIdleUploads();
  if (own_access_ == nullptr) return;  // the audit log is the sharing service's
  access_->FlushDenials();
  if (++ticks_ % 60 != 0) return;
  int64_t deleted = 0;
  const Status s = core_->ExecuteWrite([&](storage::WriteTransaction* txn) {
    StatusOr<int64_t> n = txn->TrimDeniedAudit(stream_limits_.audit_max_denied_rows);
    if (!n.ok()) return n.status();
    deleted = *n;
    return Status::Ok();
  });
  if (!s.ok()) {
    Log(LogLevel::kWarn, "audit_trim_failed", {{"error", s.ToString()}});
  } else if (deleted > 0) {
    Log(LogLevel::kInfo, "audit_trimmed",
        {{"deleted_denials", std::to_string(deleted)},
         {"kept", std::to_string(stream_limits_.audit_max_denied_rows)}});
  }
}

grpc::ServerBidiReactor<grpc::ByteBuffer, grpc::ByteBuffer>* MapServiceImpl::Ingest(
    grpc::CallbackServerContext* context, CallHold hold) {
  // Recovery first (no database read while the map is rebuilt), then the
  // stream limits: a flood of opens costs one refusal each, before any token
  // lookup or audit row (the per-client bucket also bounds the refused writes
  // audited below).
  if (Status ready = core_->CheckReady(); !ready.ok())
    return new RefusedIngest(ToGrpcStatus(ready));
  StreamSlot slot;
  if (Status admitted = limiter_->TryOpen(context->peer(), &slot); !admitted.ok()) {
    Log(LogLevel::kWarn, "stream_refused",
        {{"rpc", "Ingest"}, {"peer", context->peer()}, {"why", admitted.message()}});
    return new RefusedIngest(ToGrpcStatus(admitted));
  }
  StatusOr<Principal> who = AuthenticateToMap(*context, "Ingest");
  if (!who.ok()) return new RefusedIngest(ToGrpcStatus(who.status()));
  // The role first (a reader never writes); each batch's robot id is then
  // checked by the reactor.
  if (Status may = access_->Check(*who, Permission::kWrite, "Ingest", who->robot_id, "stream");
      !may.ok()) {
    return new RefusedIngest(ToGrpcStatus(may));
  }
  return new IngestReactor(context, core_, &ingest_options_, &ingest_streams_, access_,
                           *std::move(who), std::move(slot), std::move(hold));
}

grpc::Status MapServiceImpl::GetFeatureMap(grpc::ServerContext* context,
                                           const pb::FeatureMapRequest* request,
                                           grpc::ServerWriter<pb::FeatureMapPage>* writer) {
  if (auto p = AdmitToMap(*context, Permission::kReadMap, "GetFeatureMap"); !p.ok())
    return ToGrpcStatus(p.status());
  FeatureQuery query;
  Status s = ParseFeatureMapRequest(*request, &query);
  if (!s.ok()) return ToGrpcStatus(s);
  if (Status ready = core_->CheckReady(); !ready.ok()) return ToGrpcStatus(ready);
  // Bounded wait for the fuser (see FeatureMapRequest.max_wait_ms): never
  // past the server's cap or the call's deadline (less a margin to answer).
  double wait_s = request->max_wait_ms() == 0
                      ? stream_limits_.read_wait_s
                      : std::min(request->max_wait_ms() * 1e-3, stream_limits_.max_read_wait_s);
  const double to_deadline =
      std::chrono::duration<double>(context->deadline() - std::chrono::system_clock::now())
          .count() -
      0.05;
  query.max_wait_s = std::max(0.0, std::min(wait_s, to_deadline));
  uint64_t version = 0;
  std::vector<PlaneView> planes;
  std::vector<FusedView> features = core_->QueryFeatures(query, &version, &planes);
  pb::FeatureMapPage page;
  for (const PlaneView& p : planes) ToProto(p, page.add_planes());
  page.set_total(features.size());
  page.set_map_version(version);
  page.set_fusion_pending(core_->FusionBacklog());
  for (size_t i = 0; i < features.size(); ++i) {
    if (request->without_corner_optimisation())
      features[i].feature.segment = features[i].feature.fitted;
    ToProto(features[i], page.add_features());
    if (page.features_size() == kFeaturesPerPage) {
      if (!writer->Write(page))
        return grpc::Status(grpc::StatusCode::CANCELLED, "client went away");
      page.clear_features();
      page.clear_planes();
    }
  }
  if (page.features_size() > 0 || features.empty()) writer->Write(page);
  return grpc::Status::OK;
}

grpc::Status MapServiceImpl::WatchFeatureMap(grpc::ServerContext* context,
                                             const pb::WatchFeatureMapRequest* request,
                                             grpc::ServerWriter<pb::FeatureMapDelta>* writer) {
  if (auto p = AdmitToMap(*context, Permission::kReadMap, "WatchFeatureMap"); !p.ok())
    return ToGrpcStatus(p.status());
  if (Status ready = core_->CheckReady(); !ready.ok()) return ToGrpcStatus(ready);
  FeatureFilter filter;
  const CoreStats stats = core_->Stats();
  pb::WatchFeatureMapRequest effective = *request;
  // Just restarted from a snapshot, mapd replays what came after it: a client
  // resuming from a version the replay has not reached yet gets the map as it
  // is now (a resync), then the replay's changes.
  if (stats.replaying && effective.since_map_version() > stats.map_version) {
    effective.set_since_map_version(0);
  }
  Status s = ParseWatchRequest(effective, stats.map_version, &filter);
  if (!s.ok()) return ToGrpcStatus(s);
  return ServeWatch(core_, context, effective, filter, writer);
}

grpc::Status MapServiceImpl::ListRobots(grpc::ServerContext* context, const pb::ListRobotsRequest*,
                                        pb::ListRobotsResponse* response) {
  if (auto p = AdmitToMap(*context, Permission::kReadMap, "ListRobots"); !p.ok())
    return ToGrpcStatus(p.status());
  StatusOr<std::vector<storage::RobotSummary>> robots = core_->store().ListRobots();
  if (!robots.ok()) return ToGrpcStatus(robots.status());
  for (const auto& r : *robots) {
    pb::RobotInfo* out = response->add_robots();
    out->set_robot_id(r.name);
    out->set_first_seen_ns(r.first_seen_ns);
    out->set_last_seen_ns(r.last_seen_ns);
    out->set_batches(r.batches);
    out->set_features(r.features);
    out->set_sessions(r.sessions);
    out->set_frame_tied(r.all_sessions_tied);
  }
  return grpc::Status::OK;
}

grpc::Status MapServiceImpl::GetStats(grpc::ServerContext* context, const pb::GetStatsRequest*,
                                      pb::Stats* response) {
  StatusOr<Principal> p = AdmitToMap(*context, Permission::kReadMap, "GetStats");
  if (!p.ok()) return ToGrpcStatus(p.status());
  StatusOr<storage::StoreCounts> counts = core_->store().Counts();
  if (!counts.ok()) return ToGrpcStatus(counts.status());
  const CoreStats s = core_->Stats();
  response->set_robots(counts->robots);
  response->set_sessions(counts->sessions);
  response->set_batches(counts->observations);
  response->set_raw_features(counts->raw_features);
  response->set_fused_features(s.fused_features);
  response->set_clusters(s.clusters);
  response->set_retired_walls(s.retired_walls);
  response->set_ingest_batches_per_s(s.batches_per_s);
  response->set_ingest_features_per_s(s.features_per_s);
  response->set_uptime_s(s.uptime_s);
  response->set_db_size_bytes(core_->store().SizeBytes());
  response->set_submaps(counts->submaps);
  response->set_map_version(s.map_version);
  // Where the database (the trust root) lives is for operators: a reader's
  // or a robot's token does not learn it (issue 43).
  if (p->role == Role::kOperator || p->role == Role::kAdmin)
    response->set_db_path(core_->store().path());
  response->set_version(kVersion);
  response->set_fusion_backlog(s.fusion_backlog);
  response->set_commits(s.commits);
  response->set_recovering(s.recovering);
  response->set_replaying(s.replaying);
  response->set_snapshot_age_s(s.snapshot_age_s);
  response->set_replay_length(s.replay_length);
  response->set_fused_raw_features(s.fused_raw_features);
  response->set_fusion_nodes(s.fusion_nodes);
  response->set_fused_planes(s.fused_planes);
  response->set_write_failure(s.write_failure);
  response->set_fusion_share_refused(s.fusion_share_refused);
  for (const CoreStats::RobotShare& r : s.fusion_shares) {
    pb::RobotFusionShare* out = response->add_fusion_shares();
    out->set_robot_id(r.robot);
    out->set_pending(r.pending);
    out->set_cost_per_obs_s(r.cost_per_obs_s);
    out->set_refused(r.refused);
  }
  if (counts->raw_features > 0) {
    response->set_bytes_per_raw_feature(static_cast<double>(core_->store().SizeBytes()) /
                                        static_cast<double>(counts->raw_features));
  }
  return grpc::Status::OK;
}

grpc::ServerReadReactor<pb::UploadSubmapRequest>* MapServiceImpl::UploadSubmap(
    grpc::CallbackServerContext* context, pb::SubmapInfo* response, CallHold hold) {
  using Refused = RefusedStream<grpc::ServerReadReactor<pb::UploadSubmapRequest>>;
  StreamSlot slot;
  if (Status admitted = limiter_->TryOpen(context->peer(), &slot); !admitted.ok()) {
    Log(LogLevel::kWarn, "stream_refused",
        {{"rpc", "UploadSubmap"}, {"peer", context->peer()}, {"why", admitted.message()}});
    return new Refused(ToGrpcStatus(admitted));
  }
  StatusOr<Principal> p = AuthenticateToMap(*context, "UploadSubmap");
  if (!p.ok()) return new Refused(ToGrpcStatus(p.status()));
  // The role here; the header's robot id once it is read (UploadReactor).
  if (Status may = access_->Check(*p, Permission::kWrite, "UploadSubmap", p->robot_id, "upload");
      !may.ok()) {
    return new Refused(ToGrpcStatus(may));
  }
  if (draining_)
    return new Refused(grpc::Status(grpc::StatusCode::UNAVAILABLE, "mapd is shutting down"));
  return submaps_.Upload(context, response, std::move(slot), *std::move(p), std::move(hold));
}
grpc::Status MapServiceImpl::ListSubmaps(grpc::ServerContext* context,
                                         const pb::ListSubmapsRequest* request,
                                         pb::ListSubmapsResponse* response) {
  StatusOr<Principal> p = AuthenticateToMap(*context, "ListSubmaps");
  if (!p.ok()) return ToGrpcStatus(p.status());
  pb::ListSubmapsRequest scoped = *request;
  // A robot lists its own submaps unless it names another robot (refused).
  if (p->role == Role::kRobot && !p->anonymous && scoped.robot_id().empty())
    scoped.set_robot_id(p->robot_id);
  if (Status may = Authorize(*p, Permission::kReadSubmaps, "ListSubmaps", scoped.robot_id());
      !may.ok()) {
    return ToGrpcStatus(may);
  }
  return submaps_.List(scoped, response);
}
grpc::Status MapServiceImpl::GetSubmap(grpc::ServerContext* context,
                                       const pb::GetSubmapRequest* request,
                                       grpc::ServerWriter<pb::DataChunk>* writer) {
  StatusOr<Principal> p = AuthenticateToMap(*context, "GetSubmap");
  if (!p.ok()) return ToGrpcStatus(p.status());
  if (p->role == Role::kRobot && !p->anonymous) {
    StatusOr<storage::SubmapMeta> meta =
        core_->store().GetSubmap(static_cast<int64_t>(request->id()));
    if (!meta.ok()) return ToGrpcStatus(meta.status());
    if (Status may = Authorize(*p, Permission::kReadSubmaps, "GetSubmap", meta->robot); !may.ok()) {
      return ToGrpcStatus(may);
    }
  }
  return submaps_.Get(context, *request, writer);
}
grpc::Status MapServiceImpl::DeleteSubmap(grpc::ServerContext* context,
                                          const pb::DeleteSubmapRequest* request,
                                          pb::DeleteSubmapResponse*) {
  StatusOr<Principal> p = AuthenticateToMap(*context, "DeleteSubmap");
  if (!p.ok()) return ToGrpcStatus(p.status());
  return submaps_.Delete(*request, *p);
}
grpc::Status MapServiceImpl::MergeSubmaps(grpc::ServerContext* context,
                                          const pb::MergeSubmapsRequest* request,
                                          grpc::ServerWriter<pb::MergeProgress>* writer) {
  std::string inputs;
  for (const uint64_t id : request->submap_ids())
    inputs += (inputs.empty() ? "submaps " : ",") + std::to_string(id);
  StatusOr<Principal> p = AdmitToMap(*context, Permission::kMerge, "MergeSubmaps", "", inputs);
  if (!p.ok()) return ToGrpcStatus(p.status());
  return submaps_.Merge(context, *request, writer, *p);
}
grpc::Status MapServiceImpl::GetGlobalMap(grpc::ServerContext* context,
                                          const pb::GetGlobalMapRequest*,
                                          grpc::ServerWriter<pb::DataChunk>* writer) {
  if (auto p = AdmitToMap(*context, Permission::kReadMap, "GetGlobalMap"); !p.ok())
    return ToGrpcStatus(p.status());
  return submaps_.GetGlobalMap(context, writer);
}

grpc::Status MapServiceImpl::ListMerges(grpc::ServerContext* context,
                                        const pb::ListMergesRequest* request,
                                        pb::ListMergesResponse* response) {
  if (auto p = AdmitToMap(*context, Permission::kReadMap, "ListMerges"); !p.ok())
    return ToGrpcStatus(p.status());
  return submaps_.ListMerges(*request, response);
}
grpc::Status MapServiceImpl::GetMerge(grpc::ServerContext* context,
                                      const pb::GetMergeRequest* request,
                                      pb::MergeRecord* response) {
  if (auto p = AdmitToMap(*context, Permission::kReadMap, "GetMerge"); !p.ok())
    return ToGrpcStatus(p.status());
  return submaps_.GetMerge(*request, response);
}
grpc::Status MapServiceImpl::ApproveMerge(grpc::ServerContext* context,
                                          const pb::ApproveMergeRequest* request,
                                          pb::MergeRecord* response) {
  StatusOr<Principal> p = AdmitToMap(*context, Permission::kMerge, "ApproveMerge", "",
                                     "merge " + std::to_string(request->id()));
  if (!p.ok()) return ToGrpcStatus(p.status());
  return submaps_.ApproveMerge(*request, *p, response);
}
grpc::Status MapServiceImpl::RejectMerge(grpc::ServerContext* context,
                                         const pb::RejectMergeRequest* request,
                                         pb::MergeRecord* response) {
  StatusOr<Principal> p = AdmitToMap(*context, Permission::kMerge, "RejectMerge", "",
                                     "merge " + std::to_string(request->id()));
  if (!p.ok()) return ToGrpcStatus(p.status());
  return submaps_.RejectMerge(*request, *p, response);
}

grpc::Status MapServiceImpl::CreateToken(grpc::ServerContext* context,
                                         const pb::CreateTokenRequest* request,
                                         pb::CreateTokenResponse* response) {
  return auth_.CreateToken(*context, *request, response);
}
grpc::Status MapServiceImpl::ListTokens(grpc::ServerContext* context, const pb::ListTokensRequest*,
                                        pb::ListTokensResponse* response) {
  return auth_.ListTokens(*context, response);
}
grpc::Status MapServiceImpl::RevokeToken(grpc::ServerContext* context,
                                         const pb::RevokeTokenRequest* request,
                                         pb::RevokeTokenResponse* response) {
  return auth_.RevokeToken(*context, *request, response);
}
grpc::Status MapServiceImpl::ListAudit(grpc::ServerContext* context,
                                       const pb::ListAuditRequest* request,
                                       pb::ListAuditResponse* response) {
  return auth_.ListAudit(*context, *request, response);
}
grpc::Status MapServiceImpl::WhoAmI(grpc::ServerContext* context, const pb::WhoAmIRequest*,
                                    pb::WhoAmIResponse* response) {
  return auth_.WhoAmI(*context, response);
}

}  // namespace mapd::service
