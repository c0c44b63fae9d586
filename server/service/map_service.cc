#include "service/map_service.h"

#include <algorithm>
#include <chrono>
#include <cmath>

#include "service/log.h"
#include "service/refused_stream.h"
#include "service/status_mapping.h"

namespace mapd::service {
namespace {

// An Ingest stream refused at once (the map is still being recovered, or a
// stream limit): the robot reconnects and resends, as after any UNAVAILABLE.
using RefusedIngest = RefusedStream<grpc::ServerBidiReactor<grpc::ByteBuffer, grpc::ByteBuffer>>;


namespace pb = mapserver::v1;

constexpr int kFeaturesPerPage = 4096;
const char* const kVersion = MAPD_VERSION;

void ToProto(const FusedView& v, pb::FusedFeature* out) {
  const fusion::FusedFeature& f = v.feature;
  out->set_id(f.id);
  out->set_kind(v.kind == KindFilter::kPlane ? pb::FEATURE_KIND_PLANE : pb::FEATURE_KIND_LINE);
  out->mutable_a()->set_x(f.segment.a.x());
  out->mutable_a()->set_y(f.segment.a.y());
  out->mutable_b()->set_x(f.segment.b.x());
  out->mutable_b()->set_y(f.segment.b.y());
  out->set_z_min(f.z_min_m);
  out->set_z_max(f.z_max_m);
  out->set_support(f.support);
  out->set_member_count(f.member_count);
  for (const std::string& r : v.robots) out->add_robots(r);
}

Status FromProto(const pb::FeatureMapRequest& in, FeatureQuery* out) {
  if (in.has_bbox()) {
    const auto& b = in.bbox();
    for (double v : {b.min().x(), b.min().y(), b.max().x(), b.max().y()}) {
      if (!std::isfinite(v)) return Status::InvalidArgument("bbox has a non-finite coordinate");
    }
    if (b.min().x() > b.max().x() || b.min().y() > b.max().y()) {
      return Status::InvalidArgument("bbox.min must not exceed bbox.max on either axis");
    }
    out->bbox = geometry::Box2{{b.min().x(), b.min().y()}, {b.max().x(), b.max().y()}};
  }
  out->min_support = in.min_support();
  switch (in.kind()) {
    case pb::FEATURE_KIND_UNSPECIFIED: out->kind = KindFilter::kAny; break;
    case pb::FEATURE_KIND_LINE: out->kind = KindFilter::kLine; break;
    case pb::FEATURE_KIND_PLANE: out->kind = KindFilter::kPlane; break;
    default: return Status::InvalidArgument("kind has unknown value " + std::to_string(in.kind()));
  }
  return Status::Ok();
}

}  // namespace

MapServiceImpl::MapServiceImpl(MapCore* core, IngestOptions ingest_options, const SubmapOptions& submap_options,
                               const StreamLimits& stream_limits)
    : core_(core),
      ingest_options_(ingest_options),
      stream_limits_(stream_limits),
      limiter_(stream_limits),
      submaps_(core, submap_options) {}

grpc::ServerBidiReactor<grpc::ByteBuffer, grpc::ByteBuffer>* MapServiceImpl::Ingest(
    grpc::CallbackServerContext* context) {
  if (Status ready = core_->CheckReady(); !ready.ok()) return new RefusedIngest(ToGrpcStatus(ready));
  StreamSlot slot;
  if (Status admitted = limiter_.TryOpen(context->peer(), &slot); !admitted.ok()) {
    Log(LogLevel::kWarn, "stream_refused", {{"rpc", "Ingest"}, {"peer", context->peer()}, {"why", admitted.message()}});
    return new RefusedIngest(ToGrpcStatus(admitted));
  }
  return new IngestReactor(context, core_, &ingest_options_, &draining_, std::move(slot));
}

grpc::Status MapServiceImpl::GetFeatureMap(grpc::ServerContext* context,
                                           const pb::FeatureMapRequest* request,
                                           grpc::ServerWriter<pb::FeatureMapPage>* writer) {
  FeatureQuery query;
  Status s = FromProto(*request, &query);
  if (!s.ok()) return ToGrpcStatus(s);
  if (Status ready = core_->CheckReady(); !ready.ok()) return ToGrpcStatus(ready);
  // Bounded wait for the fuser (see FeatureMapRequest.max_wait_ms): never
  // past the server's cap or the call's deadline (less a margin to answer).
  double wait_s = request->max_wait_ms() == 0 ? stream_limits_.read_wait_s
                                              : std::min(request->max_wait_ms() * 1e-3, stream_limits_.max_read_wait_s);
  const double to_deadline =
      std::chrono::duration<double>(context->deadline() - std::chrono::system_clock::now()).count() - 0.05;
  query.max_wait_s = std::max(0.0, std::min(wait_s, to_deadline));
  uint64_t version = 0;
  std::vector<FusedView> features = core_->QueryFeatures(query, &version);
  pb::FeatureMapPage page;
  page.set_total(features.size());
  page.set_map_version(version);
  page.set_fusion_pending(core_->FusionBacklog());
  for (size_t i = 0; i < features.size(); ++i) {
    if (request->without_corner_optimisation()) features[i].feature.segment = features[i].feature.fitted;
    ToProto(features[i], page.add_features());
    if (page.features_size() == kFeaturesPerPage) {
      if (!writer->Write(page)) return grpc::Status(grpc::StatusCode::CANCELLED, "client went away");
      page.clear_features();
    }
  }
  if (page.features_size() > 0 || features.empty()) writer->Write(page);
  return grpc::Status::OK;
}

grpc::Status MapServiceImpl::ListRobots(grpc::ServerContext*, const pb::ListRobotsRequest*,
                                        pb::ListRobotsResponse* response) {
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

grpc::Status MapServiceImpl::GetStats(grpc::ServerContext*, const pb::GetStatsRequest*,
                                      pb::Stats* response) {
  StatusOr<storage::StoreCounts> counts = core_->store().Counts();
  if (!counts.ok()) return ToGrpcStatus(counts.status());
  const CoreStats s = core_->Stats();
  response->set_robots(counts->robots);
  response->set_sessions(counts->sessions);
  response->set_batches(counts->observations);
  response->set_raw_features(counts->raw_features);
  response->set_fused_features(s.fused_features);
  response->set_clusters(s.clusters);
  response->set_ingest_batches_per_s(s.batches_per_s);
  response->set_ingest_features_per_s(s.features_per_s);
  response->set_uptime_s(s.uptime_s);
  response->set_db_size_bytes(core_->store().SizeBytes());
  response->set_submaps(counts->submaps);
  response->set_map_version(s.map_version);
  response->set_db_path(core_->store().path());
  response->set_version(kVersion);
  response->set_fusion_backlog(s.fusion_backlog);
  response->set_commits(s.commits);
  response->set_recovering(s.recovering);
  response->set_snapshot_age_s(s.snapshot_age_s);
  response->set_replay_length(s.replay_length);
  response->set_fused_raw_features(s.fused_raw_features);
  response->set_fusion_nodes(s.fusion_nodes);
  response->set_write_failure(s.write_failure);
  if (counts->raw_features > 0) {
    response->set_bytes_per_raw_feature(static_cast<double>(core_->store().SizeBytes()) /
                                        static_cast<double>(counts->raw_features));
  }
  return grpc::Status::OK;
}

grpc::ServerReadReactor<pb::UploadSubmapRequest>* MapServiceImpl::UploadSubmap(grpc::CallbackServerContext* context,
                                                                               pb::SubmapInfo* response) {
  using Refused = RefusedStream<grpc::ServerReadReactor<pb::UploadSubmapRequest>>;
  if (draining_) return new Refused(grpc::Status(grpc::StatusCode::UNAVAILABLE, "mapd is shutting down"));
  StreamSlot slot;
  if (Status admitted = limiter_.TryOpen(context->peer(), &slot); !admitted.ok()) {
    Log(LogLevel::kWarn, "stream_refused",
        {{"rpc", "UploadSubmap"}, {"peer", context->peer()}, {"why", admitted.message()}});
    return new Refused(ToGrpcStatus(admitted));
  }
  return submaps_.Upload(context, response, std::move(slot));
}
grpc::Status MapServiceImpl::ListSubmaps(grpc::ServerContext*, const pb::ListSubmapsRequest* request,
                                         pb::ListSubmapsResponse* response) {
  return submaps_.List(*request, response);
}
grpc::Status MapServiceImpl::GetSubmap(grpc::ServerContext* context, const pb::GetSubmapRequest* request,
                                       grpc::ServerWriter<pb::DataChunk>* writer) {
  return submaps_.Get(context, *request, writer);
}
grpc::Status MapServiceImpl::DeleteSubmap(grpc::ServerContext*, const pb::DeleteSubmapRequest* request,
                                          pb::DeleteSubmapResponse*) {
  return submaps_.Delete(*request);
}
grpc::Status MapServiceImpl::MergeSubmaps(grpc::ServerContext* context, const pb::MergeSubmapsRequest* request,
                                          grpc::ServerWriter<pb::MergeProgress>* writer) {
  return submaps_.Merge(context, *request, writer);
}
grpc::Status MapServiceImpl::GetGlobalMap(grpc::ServerContext* context, const pb::GetGlobalMapRequest*,
                                          grpc::ServerWriter<pb::DataChunk>* writer) {
  return submaps_.GetGlobalMap(context, writer);
}

}  // namespace mapd::service
