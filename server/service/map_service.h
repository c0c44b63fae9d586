// The mapserver.v1.MapService implementation. Ingest (raw: the reactor parses,
// see ingest_reactor.h) and UploadSubmap (upload_reactor.h) run on gRPC's
// callback API, admitted by a StreamLimiter (stream_limiter.h); the other
// RPCs are short and use the synchronous API. Handlers translate between protobuf and
// library types and reach the state through Core (core.h). Every handler first asks
// AccessControl who calls and whether they may (auth.h has the role table);
// the streams ask before they take a place under the stream limits.
#ifndef MAPD_SERVICE_MAP_SERVICE_H_
#define MAPD_SERVICE_MAP_SERVICE_H_

#include <atomic>
#include <memory>
#include <string>

#include "mapserver/v1/map_service.grpc.pb.h"
#include "service/access_control.h"
#include "service/auth_service.h"
#include "service/core.h"
#include "service/ingest_reactor.h"
#include "service/stream_limiter.h"
#include "service/submap_service.h"
#include "service/watch_hub.h"

namespace mapd::service {

// Where a MapServiceImpl sits among the maps of one server (map_directory.h).
struct MapPlacement {
  std::string map_id = "default";
  // The service whose stream limiter, access control (tokens, audit log,
  // denial counts) and merge runner this one shares, so that limits and
  // identities are the server's, not per map; null: its own (the default
  // map's). Uploads in progress are limited per map.
  class MapServiceImpl* shared_with = nullptr;
};

class MapServiceImpl final : public mapserver::v1::MapService::WithCallbackMethod_UploadSubmap<
                                 mapserver::v1::MapService::WithRawCallbackMethod_Ingest<
                                     mapserver::v1::MapService::Service>> {
 public:
  MapServiceImpl(Core* core, IngestOptions ingest_options, const SubmapOptions& submap_options = {},
                 const StreamLimits& stream_limits = {}, AuthOptions auth_options = {},
                 MapPlacement placement = {});

  const std::string& map_id() const { return ingest_options_.map_id; }
  Core* core() const { return core_; }
  AccessControl& access() { return *access_; }

  // Housekeeping, every second: ends idle uploads.
  // Every second (MapServer's housekeeping): idle uploads expire, counted
  // denials are written as summary rows, and once a minute the denial rows
  // beyond limits.audit_max_denied_rows are deleted, oldest first.
  void Tick();
  void FlushDenials(bool all) { access_->FlushDenials(all); }
  const StreamLimiter& limiter() const { return *limiter_; }
  // Also admits the streams this instance relays to a map's owner.
  StreamLimiter& limiter() { return *limiter_; }

  // From now on new batches, uploads and merges are refused with UNAVAILABLE
  // and merges in flight are abandoned (shutdown).
  // Open watches end with UNAVAILABLE and new ones are refused.
  void StartDraining() {
    draining_ = true;
    ingest_streams_.DrainAll();
    submaps_.StartDraining();
    core_->watch_hub().Close();
  }

  grpc::ServerBidiReactor<grpc::ByteBuffer, grpc::ByteBuffer>* Ingest(
      grpc::CallbackServerContext* context) override {
    return Ingest(context, nullptr);
  }
  // The stream holds `hold` (its map) until it ends.
  grpc::ServerBidiReactor<grpc::ByteBuffer, grpc::ByteBuffer>* Ingest(
      grpc::CallbackServerContext* context, CallHold hold);

  grpc::Status GetFeatureMap(grpc::ServerContext* context,
                             const mapserver::v1::FeatureMapRequest* request,
                             grpc::ServerWriter<mapserver::v1::FeatureMapPage>* writer) override;
  // The change feed (watch_service.h); holds a synchronous thread while open.
  grpc::Status WatchFeatureMap(grpc::ServerContext* context,
                               const mapserver::v1::WatchFeatureMapRequest* request,
                               grpc::ServerWriter<mapserver::v1::FeatureMapDelta>* writer) override;
  grpc::Status ListRobots(grpc::ServerContext* context,
                          const mapserver::v1::ListRobotsRequest* request,
                          mapserver::v1::ListRobotsResponse* response) override;
  grpc::Status GetStats(grpc::ServerContext* context, const mapserver::v1::GetStatsRequest* request,
                        mapserver::v1::Stats* response) override;
  // map_service_trails.cc
  grpc::Status GetTrails(grpc::ServerContext* context,
                         const mapserver::v1::GetTrailsRequest* request,
                         grpc::ServerWriter<mapserver::v1::SessionTrail>* writer) override;

  // Voxel submaps: delegated to SubmapService (submap_service.h).
  grpc::ServerReadReactor<mapserver::v1::UploadSubmapRequest>* UploadSubmap(
      grpc::CallbackServerContext* context, mapserver::v1::SubmapInfo* response) override {
    return UploadSubmap(context, response, nullptr);
  }
  grpc::ServerReadReactor<mapserver::v1::UploadSubmapRequest>* UploadSubmap(
      grpc::CallbackServerContext* context, mapserver::v1::SubmapInfo* response, CallHold hold);
  grpc::Status ListSubmaps(grpc::ServerContext* context,
                           const mapserver::v1::ListSubmapsRequest* request,
                           mapserver::v1::ListSubmapsResponse* response) override;
  grpc::Status GetSubmap(grpc::ServerContext* context,
                         const mapserver::v1::GetSubmapRequest* request,
                         grpc::ServerWriter<mapserver::v1::DataChunk>* writer) override;
  grpc::Status DeleteSubmap(grpc::ServerContext* context,
                            const mapserver::v1::DeleteSubmapRequest* request,
                            mapserver::v1::DeleteSubmapResponse* response) override;
  grpc::Status MergeSubmaps(grpc::ServerContext* context,
                            const mapserver::v1::MergeSubmapsRequest* request,
                            grpc::ServerWriter<mapserver::v1::MergeProgress>* writer) override;
  grpc::Status GetGlobalMap(grpc::ServerContext* context,
                            const mapserver::v1::GetGlobalMapRequest* request,
                            grpc::ServerWriter<mapserver::v1::DataChunk>* writer) override;
  grpc::Status ListMerges(grpc::ServerContext* context,
                          const mapserver::v1::ListMergesRequest* request,
                          mapserver::v1::ListMergesResponse* response) override;
  grpc::Status GetMerge(grpc::ServerContext* context, const mapserver::v1::GetMergeRequest* request,
                        mapserver::v1::MergeRecord* response) override;
  grpc::Status ApproveMerge(grpc::ServerContext* context,
                            const mapserver::v1::ApproveMergeRequest* request,
                            mapserver::v1::MergeRecord* response) override;
  grpc::Status RejectMerge(grpc::ServerContext* context,
                           const mapserver::v1::RejectMergeRequest* request,
                           mapserver::v1::MergeRecord* response) override;

  // Identities and the audit log: delegated to AuthService (auth_service.h).
  grpc::Status CreateToken(grpc::ServerContext* context,
                           const mapserver::v1::CreateTokenRequest* request,
                           mapserver::v1::CreateTokenResponse* response) override;
  grpc::Status ListTokens(grpc::ServerContext* context,
                          const mapserver::v1::ListTokensRequest* request,
                          mapserver::v1::ListTokensResponse* response) override;
  grpc::Status RevokeToken(grpc::ServerContext* context,
                           const mapserver::v1::RevokeTokenRequest* request,
                           mapserver::v1::RevokeTokenResponse* response) override;
  grpc::Status ListAudit(grpc::ServerContext* context,
                         const mapserver::v1::ListAuditRequest* request,
                         mapserver::v1::ListAuditResponse* response) override;
  grpc::Status WhoAmI(grpc::ServerContext* context, const mapserver::v1::WhoAmIRequest* request,
                      mapserver::v1::WhoAmIResponse* response) override;

 private:
  // access_'s Authenticate and Admit, and then whether the caller may act
  // on this map (a token scoped to maps; AccessControl::CheckMap).
  StatusOr<Principal> AuthenticateToMap(const grpc::ServerContextBase& context,
                                        const std::string& action);
  StatusOr<Principal> AdmitToMap(const grpc::ServerContextBase& context, Permission permission,
                                 const std::string& action, const std::string& robot = "",
                                 const std::string& target = "");

  Core* const core_;
  const IngestOptions ingest_options_;
  const StreamLimits stream_limits_;
  std::atomic<bool> draining_{false};
  IngestStreams ingest_streams_;
  std::unique_ptr<StreamLimiter> own_limiter_;  // null when shared
  StreamLimiter* const limiter_;
  std::unique_ptr<AccessControl> own_access_;  // null when shared
  AccessControl* const access_;
  int ticks_ = 0;  // Tick() calls, from one thread
  SubmapService submaps_;
  AuthService auth_;
};

}  // namespace mapd::service

#endif  // MAPD_SERVICE_MAP_SERVICE_H_
