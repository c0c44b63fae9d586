#include "service/map_forwarder.h"

#include "service/map_router.h"

namespace mapd::service {
namespace {

std::string Value(const grpc::ServerContextBase& context, const char* key) {
  const auto& metadata = context.client_metadata();
  auto it = metadata.find(key);
  return it == metadata.end() ? std::string() : std::string(it->second.data(), it->second.size());
}

}  // namespace

bool MapForwarder::MayForward(const grpc::ServerContextBase& caller) {
  if (caller.client_metadata().count(kForwardedMetadata) != 0 ||
      caller.client_metadata().count(kFollowsRedirectsMetadata) != 0) {
    return false;
  }
  // A token (or the open mode) travels with the call; a certificate does not.
  const std::shared_ptr<const grpc::AuthContext> auth = caller.auth_context();
  const bool certificate = auth != nullptr && auth->IsPeerAuthenticated();
  return !certificate || !Value(caller, "authorization").empty();
}

MapForwarder::Peer& MapForwarder::PeerLocked(const std::string& address) {
  Peer& peer = peers_[address];
  if (peer.stub == nullptr) {
    grpc::ChannelArguments args;
    args.SetMaxReceiveMessageSize(max_message_bytes_);
    args.SetMaxSendMessageSize(max_message_bytes_);
    std::shared_ptr<grpc::Channel> channel = grpc::CreateCustomChannel(address, credentials_, args);
    peer.stub = mapserver::v1::MapService::NewStub(channel);
    peer.generic = std::make_unique<grpc::GenericStub>(channel);
  }
  return peer;
}

mapserver::v1::MapService::Stub* MapForwarder::StubTo(const std::string& address) {
  std::lock_guard<std::mutex> lock(mu_);
  return PeerLocked(address).stub.get();
}

grpc::GenericStub* MapForwarder::GenericStubTo(const std::string& address) {
  std::lock_guard<std::mutex> lock(mu_);
  return PeerLocked(address).generic.get();
}

std::unique_ptr<grpc::ClientContext> MapForwarder::ContextFor(
    const grpc::ServerContextBase& caller) const {
  auto context = std::make_unique<grpc::ClientContext>();
  if (caller.deadline() != std::chrono::system_clock::time_point::max())
    context->set_deadline(caller.deadline());
  for (const char* key : {"authorization", kMapIdMetadata}) {
    if (std::string v = Value(caller, key); !v.empty()) context->AddMetadata(key, v);
  }
  context->AddMetadata(kForwardedMetadata, forwarder_.empty() ? "mapd" : forwarder_);
  return context;
}

void MapForwarder::CopyRedirect(const grpc::ClientContext& from, grpc::ServerContextBase& to) {
  const auto& trailers = from.GetServerTrailingMetadata();
  for (const char* key : {kMapOwnerMetadata, kRetryAfterMetadata}) {
    auto it = trailers.find(key);
    if (it != trailers.end())
      to.AddTrailingMetadata(key, std::string(it->second.data(), it->second.size()));
  }
}

}  // namespace mapd::service
