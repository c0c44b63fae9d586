// The mapserver.v1.MapService that gRPC sees: it finds the map a call names
// (map_directory.h) and hands the call to that map's MapServiceImpl, which
// does the work. How a call names its map ("Maps" in map_service.proto):
// the request's map_id, else the call's mapd-map-id metadata, else
// "default"; a stream (Ingest, UploadSubmap) by its metadata. Tokens and
// WhoAmI are the server's and go to the default map's service, whose
// database holds them; ListAudit reads the named map's log. ListMaps,
// CreateMap, DeleteMap and RestoreMap are answered here (map_lifecycle.h).
//
// Each call holds its map (MapHold) until it returns, a stream until it
// ends, so that a deleted map is freed only once no call uses it.
#ifndef MAPD_SERVICE_MAP_ROUTER_H_
#define MAPD_SERVICE_MAP_ROUTER_H_

#include <functional>
#include <mutex>
#include <optional>
#include <string>

#include "mapserver/v1/map_service.grpc.pb.h"
#include "service/map_directory.h"
#include "service/map_forwarder.h"
#include "service/map_lifecycle.h"
#include "service/map_locator.h"
#include "service/stream_limiter.h"

namespace mapd::service {

inline constexpr char kMapIdMetadata[] = "mapd-map-id";
// Trailing metadata of a call refused because its map is served by another
// mapd on the same database: that instance's address (host:port). Clients
// call it there (RobotClient, mapctl, the Python client follow it).
inline constexpr char kMapOwnerMetadata[] = "mapd-map-owner";
// With a call refused because its map is being taken over: how soon to
// retry, milliseconds (the takeover rounds' period).
inline constexpr char kRetryAfterMetadata[] = "mapd-retry-after-ms";

class MapRouter final : public mapserver::v1::MapService::WithCallbackMethod_UploadSubmap<
                            mapserver::v1::MapService::WithRawCallbackMethod_Ingest<
                                mapserver::v1::MapService::Service>> {
 public:
  // `lifecycle` makes, deletes and restores maps; `locator` (PostgreSQL
  // only, else null) says where maps not served here are, and `forwarder`
  // (null: redirects only) relays calls for them (map_forwarder.h).
  MapRouter(MapDirectory* maps, MapLifecycle* lifecycle, MapLocator* locator = nullptr,
            MapForwarder* forwarder = nullptr)
      : maps_(maps), lifecycle_(lifecycle), locator_(locator), forwarder_(forwarder) {}
  // Where clients reach this server (LocateMap), once it is known (the
  // port is bound after the router is made).
  void set_address(const std::string& address);

  // The map a call names: `field` (a request's map_id), else the metadata,
  // else "default". InvalidArgument when both are set and differ, or when
  // the metadata is not a map id.
  static StatusOr<std::string> MapIdOf(const grpc::ServerContextBase& context,
                                       const std::string& field);

  grpc::ServerBidiReactor<grpc::ByteBuffer, grpc::ByteBuffer>* Ingest(
      grpc::CallbackServerContext* context) override;
  grpc::ServerReadReactor<mapserver::v1::UploadSubmapRequest>* UploadSubmap(
      grpc::CallbackServerContext* context, mapserver::v1::SubmapInfo* response) override;

  grpc::Status GetFeatureMap(grpc::ServerContext* context,
                             const mapserver::v1::FeatureMapRequest* request,
                             grpc::ServerWriter<mapserver::v1::FeatureMapPage>* writer) override;
  grpc::Status WatchFeatureMap(grpc::ServerContext* context,
                               const mapserver::v1::WatchFeatureMapRequest* request,
                               grpc::ServerWriter<mapserver::v1::FeatureMapDelta>* writer) override;
  grpc::Status ListRobots(grpc::ServerContext* context,
                          const mapserver::v1::ListRobotsRequest* request,
                          mapserver::v1::ListRobotsResponse* response) override;
  grpc::Status GetStats(grpc::ServerContext* context, const mapserver::v1::GetStatsRequest* request,
                        mapserver::v1::Stats* response) override;
  grpc::Status GetTrails(grpc::ServerContext* context,
                         const mapserver::v1::GetTrailsRequest* request,
                         grpc::ServerWriter<mapserver::v1::SessionTrail>* writer) override;
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

  grpc::Status ListMaps(grpc::ServerContext* context, const mapserver::v1::ListMapsRequest* request,
                        mapserver::v1::ListMapsResponse* response) override;
  grpc::Status CreateMap(grpc::ServerContext* context,
                         const mapserver::v1::CreateMapRequest* request,
                         mapserver::v1::MapInfo* response) override;
  grpc::Status LocateMap(grpc::ServerContext* context,
                         const mapserver::v1::LocateMapRequest* request,
                         mapserver::v1::MapLocation* response) override;
  grpc::Status DeleteMap(grpc::ServerContext* context,
                         const mapserver::v1::DeleteMapRequest* request,
                         mapserver::v1::DeleteMapResponse* response) override;
  grpc::Status RestoreMap(grpc::ServerContext* context,
                          const mapserver::v1::RestoreMapRequest* request,
                          mapserver::v1::MapInfo* response) override;

 private:
  // The same call made on the map's owner (another mapd), by its stub.
  using Remote =
      std::function<grpc::Status(mapserver::v1::MapService::Stub*, grpc::ClientContext*)>;
  // Runs `call` on the service of the map the call names, or `remote` on
  // the mapd that serves it (forwarding), or answers why not.
  grpc::Status Forward(grpc::ServerContextBase& context, const std::string& field,
                       const std::function<grpc::Status(MapServiceImpl*)>& call,
                       const Remote& remote);
  // The map `id` names, or why it is not served here: UNAVAILABLE with the
  // owner's address in kMapOwnerMetadata when another mapd serves it, or,
  // with `forward_to` and forwarding on, that address in *forward_to.
  StatusOr<MapHold> FindOrRedirect(grpc::ServerContextBase& context, const std::string& id,
                                   std::string* forward_to = nullptr);
  // A stream this instance would relay to its map's owner: its place under
  // this instance's limits.max_streams and stream_opens_per_s, or why not
  // (ResourceExhausted, logged as the local streams' refusals are).
  Status AdmitRelay(const grpc::ServerContextBase& context, const char* rpc, StreamSlot* slot);
  // The archived maps, for ListMaps.
  grpc::Status ListArchived(const Principal& caller, mapserver::v1::ListMapsResponse* response);
  // Writes `action`'s row in the server's audit log; the error when it failed.
  Status Audit(const Principal& caller, const std::string& action, const std::string& target,
               const Status& result);
  MapServiceImpl* server_wide() const { return &maps_->server_wide(); }
  // Whether `owner` is this mapd (the address it advertises): a map leased
  // here that is not in maps_ yet is being opened.
  bool IsSelf(const MapOwner& owner) const;

  MapDirectory* const maps_;
  MapLifecycle* const lifecycle_;
  MapLocator* const locator_;
  MapForwarder* const forwarder_;
  mutable std::mutex address_mu_;
  std::string address_;  // GUARDED_BY(address_mu_)
};

}  // namespace mapd::service

#endif  // MAPD_SERVICE_MAP_ROUTER_H_
