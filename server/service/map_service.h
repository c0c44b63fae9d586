// The mapserver.v1.MapService implementation. Ingest (raw: the reactor parses,
// see ingest_reactor.h) and UploadSubmap (upload_reactor.h) run on gRPC's
// callback API, admitted by a StreamLimiter (stream_limiter.h); the other
// RPCs are short and use the synchronous API. Handlers translate between protobuf and
// library types and reach the state through MapCore.
#ifndef MAPD_SERVICE_MAP_SERVICE_H_
#define MAPD_SERVICE_MAP_SERVICE_H_

#include <atomic>
#include <memory>

#include "mapserver/v1/map_service.grpc.pb.h"
#include "service/ingest_reactor.h"
#include "service/map_core.h"
#include "service/stream_limiter.h"
#include "service/submap_service.h"

namespace mapd::service {

class MapServiceImpl final
    : public mapserver::v1::MapService::WithCallbackMethod_UploadSubmap<
          mapserver::v1::MapService::WithRawCallbackMethod_Ingest<mapserver::v1::MapService::Service>> {
 public:
  MapServiceImpl(MapCore* core, IngestOptions ingest_options, const SubmapOptions& submap_options = {},
                 const StreamLimits& stream_limits = {});

  // Housekeeping, every second: ends idle uploads.
  void Tick() { submaps_.ExpireIdleUploads(); }
  const StreamLimiter& limiter() const { return limiter_; }

  // From now on new batches, uploads and merges are refused with UNAVAILABLE
  // and merges in flight are abandoned (shutdown).
  void StartDraining() {
    draining_ = true;
    submaps_.StartDraining();
  }

  grpc::ServerBidiReactor<grpc::ByteBuffer, grpc::ByteBuffer>* Ingest(
      grpc::CallbackServerContext* context) override;

  grpc::Status GetFeatureMap(grpc::ServerContext* context,
                             const mapserver::v1::FeatureMapRequest* request,
                             grpc::ServerWriter<mapserver::v1::FeatureMapPage>* writer) override;
  grpc::Status ListRobots(grpc::ServerContext* context, const mapserver::v1::ListRobotsRequest* request,
                          mapserver::v1::ListRobotsResponse* response) override;
  grpc::Status GetStats(grpc::ServerContext* context, const mapserver::v1::GetStatsRequest* request,
                        mapserver::v1::Stats* response) override;

  // Voxel submaps: delegated to SubmapService (submap_service.h).
  grpc::ServerReadReactor<mapserver::v1::UploadSubmapRequest>* UploadSubmap(
      grpc::CallbackServerContext* context, mapserver::v1::SubmapInfo* response) override;
  grpc::Status ListSubmaps(grpc::ServerContext* context, const mapserver::v1::ListSubmapsRequest* request,
                           mapserver::v1::ListSubmapsResponse* response) override;
  grpc::Status GetSubmap(grpc::ServerContext* context, const mapserver::v1::GetSubmapRequest* request,
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

 private:
  MapCore* const core_;
  const IngestOptions ingest_options_;
  const StreamLimits stream_limits_;
  std::atomic<bool> draining_{false};
  StreamLimiter limiter_;
  SubmapService submaps_;
};

}  // namespace mapd::service

#endif  // MAPD_SERVICE_MAP_SERVICE_H_
