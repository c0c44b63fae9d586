#include "service/map_router.h"

#include <map>

#include "service/refused_stream.h"
#include "service/status_mapping.h"

namespace mapd::service {
namespace {

namespace pb = mapserver::v1;

void ToProto(ServedMap& map, pb::MapInfo* out) {
  const CoreStats s = map.core->Stats();
  out->set_map_id(map.id);
  out->set_serving(map.core->CheckReady().ok() && s.write_failure.empty());
  out->set_map_version(s.map_version);
  out->set_fused_features(s.fused_features);
  out->set_batches(s.batches_stored);
  for (const auto& [key, value] : map.settings) (*out->mutable_settings())[key] = value;
}

}  // namespace

StatusOr<std::string> MapRouter::MapIdOf(const grpc::ServerContextBase& context,
                                         const std::string& field) {
  std::string from_metadata;
  const auto& metadata = context.client_metadata();
  if (auto it = metadata.find(kMapIdMetadata); it != metadata.end()) {
    from_metadata.assign(it->second.data(), it->second.size());
    MAPD_RETURN_IF_ERROR(CheckMapId(from_metadata, std::string("metadata ") + kMapIdMetadata));
  }
  if (!field.empty() && !from_metadata.empty() && field != from_metadata) {
    return Status::InvalidArgument("map_id '" + field.substr(0, 128) + "' and metadata " +
                                   kMapIdMetadata + " '" + from_metadata +
                                   "' name different maps; name one");
  }
  if (!field.empty()) return field;
  return from_metadata.empty() ? std::string(kDefaultMapId) : from_metadata;
}

StatusOr<ServedMap*> MapRouter::FindOrRedirect(grpc::ServerContextBase& context,
                                               const std::string& id) {
  StatusOr<ServedMap*> map = maps_->Find(id);
  if (map.ok() || locator_ == nullptr) return map;
  const std::string key = id.empty() ? std::string(kDefaultMapId) : id;
  std::optional<MapOwner> owner = locator_->Locate(key);
  // Taken over since the last round, or before the first one?
  if (!owner || !owner->live) owner = locator_->LocateNow(key);
  if (!owner) return map;  // no such map
  if (!owner->live || owner->address.empty()) {
    context.AddTrailingMetadata(kRetryAfterMetadata, std::to_string(locator_->retry_after_ms()));
    return Status::Unavailable("map '" + id +
                               "' is being taken over by another mapd (its owner stopped); "
                               "retry in a few seconds");
  }
  context.AddTrailingMetadata(kMapOwnerMetadata, owner->address);
  return Status::Unavailable("map '" + id + "' is served by the mapd at " + owner->address +
                             " (instance '" + owner->instance + "'); call it there");
}

grpc::Status MapRouter::Forward(grpc::ServerContextBase& context, const std::string& field,
                                const std::function<grpc::Status(MapServiceImpl*)>& call) {
  StatusOr<std::string> id = MapIdOf(context, field);
  if (!id.ok()) return ToGrpcStatus(id.status());
  StatusOr<ServedMap*> map = FindOrRedirect(context, *id);
  if (!map.ok()) return ToGrpcStatus(map.status());
  return call((*map)->service.get());
}

grpc::ServerBidiReactor<grpc::ByteBuffer, grpc::ByteBuffer>* MapRouter::Ingest(
    grpc::CallbackServerContext* context) {
  using Refused = RefusedStream<grpc::ServerBidiReactor<grpc::ByteBuffer, grpc::ByteBuffer>>;
  StatusOr<std::string> id = MapIdOf(*context, "");
  if (!id.ok()) return new Refused(ToGrpcStatus(id.status()));
  StatusOr<ServedMap*> map = FindOrRedirect(*context, *id);
  if (!map.ok()) return new Refused(ToGrpcStatus(map.status()));
  return (*map)->service->Ingest(context);
}

grpc::ServerReadReactor<pb::UploadSubmapRequest>* MapRouter::UploadSubmap(
    grpc::CallbackServerContext* context, pb::SubmapInfo* response) {
  using Refused = RefusedStream<grpc::ServerReadReactor<pb::UploadSubmapRequest>>;
  StatusOr<std::string> id = MapIdOf(*context, "");
  if (!id.ok()) return new Refused(ToGrpcStatus(id.status()));
  StatusOr<ServedMap*> map = FindOrRedirect(*context, *id);
  if (!map.ok()) return new Refused(ToGrpcStatus(map.status()));
  return (*map)->service->UploadSubmap(context, response);
}

grpc::Status MapRouter::GetFeatureMap(grpc::ServerContext* c, const pb::FeatureMapRequest* r,
                                      grpc::ServerWriter<pb::FeatureMapPage>* w) {
  return Forward(*c, r->map_id(), [&](MapServiceImpl* m) { return m->GetFeatureMap(c, r, w); });
}
grpc::Status MapRouter::WatchFeatureMap(grpc::ServerContext* c, const pb::WatchFeatureMapRequest* r,
                                        grpc::ServerWriter<pb::FeatureMapDelta>* w) {
  return Forward(*c, r->map_id(), [&](MapServiceImpl* m) { return m->WatchFeatureMap(c, r, w); });
}
grpc::Status MapRouter::ListRobots(grpc::ServerContext* c, const pb::ListRobotsRequest* r,
                                   pb::ListRobotsResponse* out) {
  return Forward(*c, r->map_id(), [&](MapServiceImpl* m) { return m->ListRobots(c, r, out); });
}
grpc::Status MapRouter::GetStats(grpc::ServerContext* c, const pb::GetStatsRequest* r,
                                 pb::Stats* out) {
  return Forward(*c, r->map_id(), [&](MapServiceImpl* m) { return m->GetStats(c, r, out); });
}
grpc::Status MapRouter::GetTrails(grpc::ServerContext* c, const pb::GetTrailsRequest* r,
                                  grpc::ServerWriter<pb::SessionTrail>* w) {
  return Forward(*c, r->map_id(), [&](MapServiceImpl* m) { return m->GetTrails(c, r, w); });
}
grpc::Status MapRouter::ListSubmaps(grpc::ServerContext* c, const pb::ListSubmapsRequest* r,
                                    pb::ListSubmapsResponse* out) {
  return Forward(*c, r->map_id(), [&](MapServiceImpl* m) { return m->ListSubmaps(c, r, out); });
}
grpc::Status MapRouter::GetSubmap(grpc::ServerContext* c, const pb::GetSubmapRequest* r,
                                  grpc::ServerWriter<pb::DataChunk>* w) {
  return Forward(*c, r->map_id(), [&](MapServiceImpl* m) { return m->GetSubmap(c, r, w); });
}
grpc::Status MapRouter::DeleteSubmap(grpc::ServerContext* c, const pb::DeleteSubmapRequest* r,
                                     pb::DeleteSubmapResponse* out) {
  return Forward(*c, r->map_id(), [&](MapServiceImpl* m) { return m->DeleteSubmap(c, r, out); });
}
grpc::Status MapRouter::MergeSubmaps(grpc::ServerContext* c, const pb::MergeSubmapsRequest* r,
                                     grpc::ServerWriter<pb::MergeProgress>* w) {
  return Forward(*c, r->map_id(), [&](MapServiceImpl* m) { return m->MergeSubmaps(c, r, w); });
}
grpc::Status MapRouter::GetGlobalMap(grpc::ServerContext* c, const pb::GetGlobalMapRequest* r,
                                     grpc::ServerWriter<pb::DataChunk>* w) {
  return Forward(*c, r->map_id(), [&](MapServiceImpl* m) { return m->GetGlobalMap(c, r, w); });
}
grpc::Status MapRouter::ListMerges(grpc::ServerContext* c, const pb::ListMergesRequest* r,
                                   pb::ListMergesResponse* out) {
  return Forward(*c, r->map_id(), [&](MapServiceImpl* m) { return m->ListMerges(c, r, out); });
}
grpc::Status MapRouter::GetMerge(grpc::ServerContext* c, const pb::GetMergeRequest* r,
                                 pb::MergeRecord* out) {
  return Forward(*c, r->map_id(), [&](MapServiceImpl* m) { return m->GetMerge(c, r, out); });
}
grpc::Status MapRouter::ApproveMerge(grpc::ServerContext* c, const pb::ApproveMergeRequest* r,
                                     pb::MergeRecord* out) {
  return Forward(*c, r->map_id(), [&](MapServiceImpl* m) { return m->ApproveMerge(c, r, out); });
}
grpc::Status MapRouter::RejectMerge(grpc::ServerContext* c, const pb::RejectMergeRequest* r,
                                    pb::MergeRecord* out) {
  return Forward(*c, r->map_id(), [&](MapServiceImpl* m) { return m->RejectMerge(c, r, out); });
}

grpc::Status MapRouter::CreateToken(grpc::ServerContext* c, const pb::CreateTokenRequest* r,
                                    pb::CreateTokenResponse* out) {
  return server_wide()->CreateToken(c, r, out);
}
grpc::Status MapRouter::ListTokens(grpc::ServerContext* c, const pb::ListTokensRequest* r,
                                   pb::ListTokensResponse* out) {
  return server_wide()->ListTokens(c, r, out);
}
grpc::Status MapRouter::RevokeToken(grpc::ServerContext* c, const pb::RevokeTokenRequest* r,
                                    pb::RevokeTokenResponse* out) {
  return server_wide()->RevokeToken(c, r, out);
}
grpc::Status MapRouter::ListAudit(grpc::ServerContext* c, const pb::ListAuditRequest* r,
                                  pb::ListAuditResponse* out) {
  return Forward(*c, r->map_id(), [&](MapServiceImpl* m) { return m->ListAudit(c, r, out); });
}
grpc::Status MapRouter::WhoAmI(grpc::ServerContext* c, const pb::WhoAmIRequest* r,
                               pb::WhoAmIResponse* out) {
  return server_wide()->WhoAmI(c, r, out);
}

grpc::Status MapRouter::ListMaps(grpc::ServerContext* context, const pb::ListMapsRequest*,
                                 pb::ListMapsResponse* response) {
  StatusOr<Principal> p = server_wide()->access().Admit(*context, Permission::kReadMap, "ListMaps");
  if (!p.ok()) return ToGrpcStatus(p.status());
  std::map<std::string, pb::MapInfo> maps;
  for (ServedMap* map : maps_->List()) ToProto(*map, &maps[map->id]);
  if (locator_ != nullptr) {  // the database's other maps, and who serves them
    for (const auto& [id, owner] : locator_->Owners()) {
      if (maps.count(id) != 0) continue;
      pb::MapInfo& info = maps[id];
      info.set_map_id(id);
      info.set_served_by(owner.address);
    }
  }
  for (auto& [id, info] : maps) {
    // A token scoped to maps sees those only.
    if (AuthorizeMap(*p, id, "ListMaps").ok()) *response->add_maps() = std::move(info);
  }
  response->set_can_create(maps_->can_create());
  return grpc::Status::OK;
}

void MapRouter::set_address(const std::string& address) {
  std::lock_guard<std::mutex> lock(address_mu_);
  address_ = address;
}

grpc::Status MapRouter::LocateMap(grpc::ServerContext* context, const pb::LocateMapRequest* request,
                                  pb::MapLocation* response) {
  StatusOr<Principal> p =
      server_wide()->access().Admit(*context, Permission::kReadMap, "LocateMap");
  if (!p.ok()) return ToGrpcStatus(p.status());
  StatusOr<std::string> id = MapIdOf(*context, request->map_id());
  if (!id.ok()) return ToGrpcStatus(id.status());
  if (Status s = AuthorizeMap(*p, *id, "LocateMap"); !s.ok()) return ToGrpcStatus(s);
  response->set_map_id(*id);
  if (maps_->Find(*id).ok()) {
    std::lock_guard<std::mutex> lock(address_mu_);
    response->set_address(address_);
    response->set_here(true);
    response->set_live(true);
    return grpc::Status::OK;
  }
  std::optional<MapOwner> owner;
  if (locator_ != nullptr) {
    owner = locator_->Locate(*id);
    // Taken over, or made on another instance, since the last round?
    if (!owner || !owner->live) owner = locator_->LocateNow(*id);
  }
  if (!owner) return ToGrpcStatus(maps_->Find(*id).status());  // NotFound
  response->set_address(owner->address);
  response->set_instance(owner->instance);
  response->set_live(owner->live && !owner->address.empty());
  return grpc::Status::OK;
}

grpc::Status MapRouter::CreateMap(grpc::ServerContext* context, const pb::CreateMapRequest* request,
                                  pb::MapInfo* response) {
  const std::string target = "map " + request->map_id().substr(0, 128);
  AccessControl& access = server_wide()->access();
  StatusOr<Principal> p = access.Admit(*context, Permission::kManageMaps, "CreateMap", "", target);
  if (!p.ok()) return ToGrpcStatus(p.status());
  const MapSettings settings(request->settings().begin(), request->settings().end());
  StatusOr<ServedMap*> map = maps_->Create(request->map_id(), settings);
  // The audit row says what happened, made or not (the server's log).
  const std::string result = map.ok() ? "ok" : map.status().ToString();
  const Status audited =
      maps_->server_wide_core().ExecuteWrite([&](storage::WriteTransaction* txn) {
        return txn->AppendAudit(AccessControl::Entry(*p, "CreateMap", target, result));
      });
  if (!map.ok()) return ToGrpcStatus(map.status());
  if (on_create_) on_create_(*map);
  // An empty map recovers at once: answer once it takes batches, so that the
  // caller's next call is not UNAVAILABLE.
  (*map)->core->WaitUntilReady(std::chrono::seconds(10));
  ToProto(**map, response);
  if (!audited.ok()) {
    return grpc::Status(grpc::StatusCode::INTERNAL,
                        "map '" + request->map_id() +
                            "' was made, but its audit row was not stored: " + audited.ToString());
  }
  return grpc::Status::OK;
}

}  // namespace mapd::service
