#include "service/map_router.h"

#include <map>

#include "service/log.h"
#include "service/refused_stream.h"
#include "service/status_mapping.h"
#include "service/stream_relay.h"

namespace mapd::service {
namespace {

namespace pb = mapserver::v1;
using Stub = pb::MapService::Stub;

// A forwarded server stream: the owner's messages, written on as they come.
template <typename Message>
grpc::Status Relay(grpc::ClientContext* relayed, std::unique_ptr<grpc::ClientReader<Message>> from,
                   grpc::ServerWriter<Message>* to) {
  Message m;
  while (from->Read(&m)) {
    if (!to->Write(m)) {  // the caller went away
      relayed->TryCancel();
      break;
    }
  }
  return from->Finish();
}

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

StatusOr<MapHold> MapRouter::FindOrRedirect(grpc::ServerContextBase& context, const std::string& id,
                                            std::string* forward_to) {
  StatusOr<MapHold> map = maps_->Find(id);
  if (map.ok() || locator_ == nullptr) return map;
  const std::string key = id.empty() ? std::string(kDefaultMapId) : id;
  std::optional<MapOwner> owner = locator_->Locate(key);
  // Taken over since the last round, or before the first one? Or leased
  // here by the last round's view but not served: handed over since, or
  // still opening (read again: only maps in transition cost a query).
  if (!owner || !owner->live || IsSelf(*owner)) owner = locator_->LocateNow(key);
  if (!owner) return map;  // no such map
  if (!owner->live || owner->address.empty()) {
    context.AddTrailingMetadata(kRetryAfterMetadata, std::to_string(locator_->retry_after_ms()));
    return Status::Unavailable("map '" + id +
                               "' is being taken over by another mapd (its owner stopped); "
                               "retry in a few seconds");
  }
  if (IsSelf(*owner)) {
    // This mapd holds the lease and is opening the map (or handing it over
    // this moment): neither forward the call to itself nor send the client
    // back here.
    context.AddTrailingMetadata(kRetryAfterMetadata, std::to_string(locator_->retry_after_ms()));
    return Status::Unavailable("map '" + id +
                               "' is being opened by this mapd (taken over, its data loading); "
                               "retry in a moment");
  }
  if (forward_to != nullptr && forwarder_ != nullptr && MapForwarder::MayForward(context)) {
    *forward_to = owner->address;
    return Status::Unavailable("map '" + id + "' is served by the mapd at " + owner->address);
  }
  context.AddTrailingMetadata(kMapOwnerMetadata, owner->address);
  return Status::Unavailable("map '" + id + "' is served by the mapd at " + owner->address +
                             " (instance '" + owner->instance + "'); call it there");
}

Status MapRouter::AdmitRelay(const grpc::ServerContextBase& context, const char* rpc,
                             StreamSlot* slot) {
  Status admitted = server_wide()->limiter().TryOpen(context.peer(), slot);
  if (!admitted.ok()) {
    Log(LogLevel::kWarn, "stream_refused",
        {{"rpc", rpc}, {"peer", context.peer()}, {"relay", "true"}, {"why", admitted.message()}});
  }
  return admitted;
}

grpc::Status MapRouter::Forward(grpc::ServerContextBase& context, const std::string& field,
                                const std::function<grpc::Status(MapServiceImpl*)>& call,
                                const Remote& remote) {
  StatusOr<std::string> id = MapIdOf(context, field);
  if (!id.ok()) return ToGrpcStatus(id.status());
  std::string owner;
  StatusOr<MapHold> map = FindOrRedirect(context, *id, &owner);
  if (map.ok()) return call((*map)->service.get());  // `map` holds it until the call returns
  if (owner.empty()) return ToGrpcStatus(map.status());
  std::unique_ptr<grpc::ClientContext> relayed = forwarder_->ContextFor(context);
  const grpc::Status status = remote(forwarder_->StubTo(owner), relayed.get());
  MapForwarder::CopyRedirect(*relayed, context);
  if (status.error_code() == grpc::StatusCode::UNAVAILABLE &&
      relayed->GetServerTrailingMetadata().count(kMapOwnerMetadata) == 0) {
    // The owner did not answer: a client that follows redirects tries it itself.
    context.AddTrailingMetadata(kMapOwnerMetadata, owner);
  }
  return status;
}

grpc::ServerBidiReactor<grpc::ByteBuffer, grpc::ByteBuffer>* MapRouter::Ingest(
    grpc::CallbackServerContext* context) {
  using Refused = RefusedStream<grpc::ServerBidiReactor<grpc::ByteBuffer, grpc::ByteBuffer>>;
  StatusOr<std::string> id = MapIdOf(*context, "");
  if (!id.ok()) return new Refused(ToGrpcStatus(id.status()));
  std::string owner;
  StatusOr<MapHold> map = FindOrRedirect(*context, *id, &owner);
  if (!owner.empty()) {
    StreamSlot slot;
    if (Status s = AdmitRelay(*context, "Ingest", &slot); !s.ok()) {
      return new Refused(ToGrpcStatus(s));
    }
    return RelayIngest(context, forwarder_, owner, std::move(slot));
  }
  if (!map.ok()) return new Refused(ToGrpcStatus(map.status()));
  MapServiceImpl* service = (*map)->service.get();
  return service->Ingest(context, *std::move(map));
}

grpc::ServerReadReactor<pb::UploadSubmapRequest>* MapRouter::UploadSubmap(
    grpc::CallbackServerContext* context, pb::SubmapInfo* response) {
  using Refused = RefusedStream<grpc::ServerReadReactor<pb::UploadSubmapRequest>>;
  StatusOr<std::string> id = MapIdOf(*context, "");
  if (!id.ok()) return new Refused(ToGrpcStatus(id.status()));
  std::string owner;
  StatusOr<MapHold> map = FindOrRedirect(*context, *id, &owner);
  if (!owner.empty()) {
    StreamSlot slot;
    if (Status s = AdmitRelay(*context, "UploadSubmap", &slot); !s.ok()) {
      return new Refused(ToGrpcStatus(s));
    }
    return RelayUpload(context, response, forwarder_, owner, std::move(slot));
  }
  if (!map.ok()) return new Refused(ToGrpcStatus(map.status()));
  MapServiceImpl* service = (*map)->service.get();
  return service->UploadSubmap(context, response, *std::move(map));
}

grpc::Status MapRouter::GetFeatureMap(grpc::ServerContext* c, const pb::FeatureMapRequest* r,
                                      grpc::ServerWriter<pb::FeatureMapPage>* w) {
  return Forward(
      *c, r->map_id(), [&](MapServiceImpl* m) { return m->GetFeatureMap(c, r, w); },
      [&](Stub* s, grpc::ClientContext* cc) { return Relay(cc, s->GetFeatureMap(cc, *r), w); });
}
grpc::Status MapRouter::WatchFeatureMap(grpc::ServerContext* c, const pb::WatchFeatureMapRequest* r,
                                        grpc::ServerWriter<pb::FeatureMapDelta>* w) {
  return Forward(
      *c, r->map_id(), [&](MapServiceImpl* m) { return m->WatchFeatureMap(c, r, w); },
      [&](Stub* s, grpc::ClientContext* cc) { return Relay(cc, s->WatchFeatureMap(cc, *r), w); });
}
grpc::Status MapRouter::ListRobots(grpc::ServerContext* c, const pb::ListRobotsRequest* r,
                                   pb::ListRobotsResponse* out) {
  return Forward(
      *c, r->map_id(), [&](MapServiceImpl* m) { return m->ListRobots(c, r, out); },
      [&](Stub* s, grpc::ClientContext* cc) { return s->ListRobots(cc, *r, out); });
}
grpc::Status MapRouter::GetStats(grpc::ServerContext* c, const pb::GetStatsRequest* r,
                                 pb::Stats* out) {
  return Forward(
      *c, r->map_id(), [&](MapServiceImpl* m) { return m->GetStats(c, r, out); },
      [&](Stub* s, grpc::ClientContext* cc) { return s->GetStats(cc, *r, out); });
}
grpc::Status MapRouter::GetTrails(grpc::ServerContext* c, const pb::GetTrailsRequest* r,
                                  grpc::ServerWriter<pb::SessionTrail>* w) {
  return Forward(
      *c, r->map_id(), [&](MapServiceImpl* m) { return m->GetTrails(c, r, w); },
      [&](Stub* s, grpc::ClientContext* cc) { return Relay(cc, s->GetTrails(cc, *r), w); });
}
grpc::Status MapRouter::ListSubmaps(grpc::ServerContext* c, const pb::ListSubmapsRequest* r,
                                    pb::ListSubmapsResponse* out) {
  return Forward(
      *c, r->map_id(), [&](MapServiceImpl* m) { return m->ListSubmaps(c, r, out); },
      [&](Stub* s, grpc::ClientContext* cc) { return s->ListSubmaps(cc, *r, out); });
}
grpc::Status MapRouter::GetSubmap(grpc::ServerContext* c, const pb::GetSubmapRequest* r,
                                  grpc::ServerWriter<pb::DataChunk>* w) {
  return Forward(
      *c, r->map_id(), [&](MapServiceImpl* m) { return m->GetSubmap(c, r, w); },
      [&](Stub* s, grpc::ClientContext* cc) { return Relay(cc, s->GetSubmap(cc, *r), w); });
}
grpc::Status MapRouter::DeleteSubmap(grpc::ServerContext* c, const pb::DeleteSubmapRequest* r,
                                     pb::DeleteSubmapResponse* out) {
  return Forward(
      *c, r->map_id(), [&](MapServiceImpl* m) { return m->DeleteSubmap(c, r, out); },
      [&](Stub* s, grpc::ClientContext* cc) { return s->DeleteSubmap(cc, *r, out); });
}
grpc::Status MapRouter::MergeSubmaps(grpc::ServerContext* c, const pb::MergeSubmapsRequest* r,
                                     grpc::ServerWriter<pb::MergeProgress>* w) {
  return Forward(
      *c, r->map_id(), [&](MapServiceImpl* m) { return m->MergeSubmaps(c, r, w); },
      [&](Stub* s, grpc::ClientContext* cc) { return Relay(cc, s->MergeSubmaps(cc, *r), w); });
}
grpc::Status MapRouter::GetGlobalMap(grpc::ServerContext* c, const pb::GetGlobalMapRequest* r,
                                     grpc::ServerWriter<pb::DataChunk>* w) {
  return Forward(
      *c, r->map_id(), [&](MapServiceImpl* m) { return m->GetGlobalMap(c, r, w); },
      [&](Stub* s, grpc::ClientContext* cc) { return Relay(cc, s->GetGlobalMap(cc, *r), w); });
}
grpc::Status MapRouter::ListMerges(grpc::ServerContext* c, const pb::ListMergesRequest* r,
                                   pb::ListMergesResponse* out) {
  return Forward(
      *c, r->map_id(), [&](MapServiceImpl* m) { return m->ListMerges(c, r, out); },
      [&](Stub* s, grpc::ClientContext* cc) { return s->ListMerges(cc, *r, out); });
}
grpc::Status MapRouter::GetMerge(grpc::ServerContext* c, const pb::GetMergeRequest* r,
                                 pb::MergeRecord* out) {
  return Forward(
      *c, r->map_id(), [&](MapServiceImpl* m) { return m->GetMerge(c, r, out); },
      [&](Stub* s, grpc::ClientContext* cc) { return s->GetMerge(cc, *r, out); });
}
grpc::Status MapRouter::ApproveMerge(grpc::ServerContext* c, const pb::ApproveMergeRequest* r,
                                     pb::MergeRecord* out) {
  return Forward(
      *c, r->map_id(), [&](MapServiceImpl* m) { return m->ApproveMerge(c, r, out); },
      [&](Stub* s, grpc::ClientContext* cc) { return s->ApproveMerge(cc, *r, out); });
}
grpc::Status MapRouter::RejectMerge(grpc::ServerContext* c, const pb::RejectMergeRequest* r,
                                    pb::MergeRecord* out) {
  return Forward(
      *c, r->map_id(), [&](MapServiceImpl* m) { return m->RejectMerge(c, r, out); },
      [&](Stub* s, grpc::ClientContext* cc) { return s->RejectMerge(cc, *r, out); });
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
  return Forward(
      *c, r->map_id(), [&](MapServiceImpl* m) { return m->ListAudit(c, r, out); },
      [&](Stub* s, grpc::ClientContext* cc) { return s->ListAudit(cc, *r, out); });
}
grpc::Status MapRouter::WhoAmI(grpc::ServerContext* c, const pb::WhoAmIRequest* r,
                               pb::WhoAmIResponse* out) {
  return server_wide()->WhoAmI(c, r, out);
}

grpc::Status MapRouter::ListMaps(grpc::ServerContext* context, const pb::ListMapsRequest* request,
                                 pb::ListMapsResponse* response) {
  StatusOr<Principal> p = server_wide()->access().Admit(*context, Permission::kReadMap, "ListMaps");
  if (!p.ok()) return ToGrpcStatus(p.status());
  response->set_can_create(maps_->can_create());
  if (request->archived()) return ListArchived(*p, response);
  std::map<std::string, pb::MapInfo> maps;
  for (const MapHold& map : maps_->List()) ToProto(*map, &maps[map->id]);
  if (locator_ != nullptr) {  // the database's other maps, and who serves them
    for (const auto& [id, owner] : locator_->Owners()) {
      if (maps.count(id) != 0) continue;
      pb::MapInfo& info = maps[id];
      info.set_map_id(id);
      // Leased here and still opening: served here, not serving yet.
      if (!IsSelf(owner)) info.set_served_by(owner.address);
    }
  }
  for (auto& [id, info] : maps) {
    // A token scoped to maps sees those only.
    if (AuthorizeMap(*p, id, "ListMaps").ok()) *response->add_maps() = std::move(info);
  }
  return grpc::Status::OK;
}

grpc::Status MapRouter::ListArchived(const Principal& caller, pb::ListMapsResponse* response) {
  StatusOr<std::vector<ArchivedMap>> archived = lifecycle_->ListArchived();
  if (!archived.ok()) return ToGrpcStatus(archived.status());
  for (const ArchivedMap& a : *archived) {
    if (!AuthorizeMap(caller, a.id, "ListMaps").ok()) continue;
    pb::MapInfo* info = response->add_maps();
    info->set_map_id(a.id);
    info->set_archived_ns(a.archived_ns);
  }
  return grpc::Status::OK;
}

Status MapRouter::Audit(const Principal& caller, const std::string& action,
                        const std::string& target, const Status& result) {
  return maps_->server_wide_core().ExecuteWrite([&](storage::WriteTransaction* txn) {
    return txn->AppendAudit(
        AccessControl::Entry(caller, action, target, result.ok() ? "ok" : result.ToString()));
  });
}

void MapRouter::set_address(const std::string& address) {
  std::lock_guard<std::mutex> lock(address_mu_);
  address_ = address;
}

bool MapRouter::IsSelf(const MapOwner& owner) const {
  std::lock_guard<std::mutex> lock(address_mu_);
  return !owner.address.empty() && owner.address == address_;
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
  response->set_here(IsSelf(*owner));  // leased here, still opening
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
  StatusOr<MapHold> map = maps_->Create(request->map_id(), settings);
  // The audit row says what happened, made or not (the server's log).
  const Status audited = Audit(*p, "CreateMap", target, map.status());
  if (!map.ok()) return ToGrpcStatus(map.status());
  lifecycle_->Created(map->get());
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

grpc::Status MapRouter::DeleteMap(grpc::ServerContext* context, const pb::DeleteMapRequest* request,
                                  pb::DeleteMapResponse* response) {
  const std::string& id = request->map_id();
  const std::string target = "map " + id.substr(0, 128) + (request->purge() ? " (purge)" : "");
  StatusOr<Principal> p =
      server_wide()->access().Admit(*context, Permission::kManageMaps, "DeleteMap", "", target);
  if (!p.ok()) return ToGrpcStatus(p.status());
  if (Status s = CheckMapId(id, "map_id"); !s.ok()) return ToGrpcStatus(s);
  StatusOr<std::string> where = lifecycle_->DeleteMap(id, request->purge());
  if (where.status().code() == StatusCode::kNotFound && locator_ != nullptr) {
    // Served by another mapd of the database? Then the caller goes there.
    StatusOr<MapHold> elsewhere = FindOrRedirect(*context, id);
    if (!elsewhere.ok() && elsewhere.status().code() != StatusCode::kNotFound)
      return ToGrpcStatus(elsewhere.status());
  }
  const Status audited = Audit(*p, "DeleteMap", target, where.status());
  if (!where.ok()) return ToGrpcStatus(where.status());
  response->set_map_id(id);
  response->set_purged(request->purge());
  response->set_where(*where);
  if (!audited.ok()) {
    return grpc::Status(grpc::StatusCode::INTERNAL, "map '" + id +
                                                        "' was deleted, but its audit row was "
                                                        "not stored: " +
                                                        audited.ToString());
  }
  return grpc::Status::OK;
}

grpc::Status MapRouter::RestoreMap(grpc::ServerContext* context,
                                   const pb::RestoreMapRequest* request, pb::MapInfo* response) {
  const std::string& id = request->map_id();
  const std::string target = "map " + id.substr(0, 128);
  StatusOr<Principal> p =
      server_wide()->access().Admit(*context, Permission::kManageMaps, "RestoreMap", "", target);
  if (!p.ok()) return ToGrpcStatus(p.status());
  if (Status s = CheckMapId(id, "map_id"); !s.ok()) return ToGrpcStatus(s);
  StatusOr<MapHold> map = lifecycle_->RestoreMap(id);
  const Status audited = Audit(*p, "RestoreMap", target, map.status());
  if (!map.ok()) return ToGrpcStatus(map.status());
  response->set_map_id(id);
  if (*map != nullptr) {
    // Answer once it takes batches (a restored map recovers its fused map).
    (*map)->core->WaitUntilReady(std::chrono::seconds(30));
    ToProto(**map, response);
  } else if (locator_ != nullptr) {
    if (std::optional<MapOwner> owner = locator_->LocateNow(id)) {
      response->set_served_by(owner->address);
    }
  }
  if (!audited.ok()) {
    return grpc::Status(grpc::StatusCode::INTERNAL, "map '" + id +
                                                        "' was restored, but its audit row was "
                                                        "not stored: " +
                                                        audited.ToString());
  }
  return grpc::Status::OK;
}

}  // namespace mapd::service
