// Forwarding (docs/scale-out.md, "Redirects and clients"): with several mapd
// on one database, a call for a map another instance serves is relayed to
// that instance and its answer returned, for clients that know one address
// and do not follow redirects (grpcurl, scripts, clients from before
// redirects). Every map call is forwarded: unary and server-streaming ones
// by MapRouter, streams of batches and uploads by stream_relay.h.
//
// The forwarded call carries the caller's token, map and deadline, and
// kForwardedMetadata: a forwarded call is never forwarded again (two
// instances with stale views cannot bounce it between them); it is answered
// where it lands, with the owner's redirect metadata copied back. A caller
// known by its client certificate (mTLS) is not forwarded: the owner would
// see this instance's identity, not the caller's.
//
// Thread safety: every method may be called from any thread.
#ifndef MAPD_SERVICE_MAP_FORWARDER_H_
#define MAPD_SERVICE_MAP_FORWARDER_H_

#include <grpcpp/generic/generic_stub.h>
#include <grpcpp/grpcpp.h>

#include <map>
#include <memory>
#include <mutex>
#include <string>

#include "mapserver/v1/map_service.grpc.pb.h"

namespace mapd::service {

inline constexpr char kForwardedMetadata[] = "mapd-forwarded-by";
// Sent by clients that follow redirects themselves (RobotClient with
// `connect`, in C++ and Python): they are redirected to the owner rather
// than relayed, which spares every later message a hop.
inline constexpr char kFollowsRedirectsMetadata[] = "mapd-follows-redirects";

class MapForwarder {
 public:
  // `credentials`: how to reach the other instances (plaintext, or TLS with
  // the CA of their certificates); `forwarder`: this instance's name, sent
  // in kForwardedMetadata.
  MapForwarder(std::shared_ptr<grpc::ChannelCredentials> credentials, std::string forwarder,
               int max_message_bytes)
      : credentials_(std::move(credentials)),
        forwarder_(std::move(forwarder)),
        max_message_bytes_(max_message_bytes) {}

  // Whether `caller`'s call may be forwarded: not forwarded already, from a
  // client that does not follow redirects, not known by a client
  // certificate alone.
  static bool MayForward(const grpc::ServerContextBase& caller);
  // Stubs for the mapd at `address` (host:port); channels are kept.
  mapserver::v1::MapService::Stub* StubTo(const std::string& address);
  grpc::GenericStub* GenericStubTo(const std::string& address);
  // The forwarded call's context: `caller`'s deadline, token and map.
  std::unique_ptr<grpc::ClientContext> ContextFor(const grpc::ServerContextBase& caller) const;
  // The owner's redirect metadata (a map that moved meanwhile), copied
  // back to the caller.
  static void CopyRedirect(const grpc::ClientContext& from, grpc::ServerContextBase& to);

 private:
  const std::shared_ptr<grpc::ChannelCredentials> credentials_;
  const std::string forwarder_;
  const int max_message_bytes_;
  struct Peer {
    std::unique_ptr<mapserver::v1::MapService::Stub> stub;
    std::unique_ptr<grpc::GenericStub> generic;
  };
  Peer& PeerLocked(const std::string& address);  // REQUIRES: mu_ held

  std::mutex mu_;
  std::map<std::string, Peer> peers_;  // GUARDED_BY(mu_)
};

}  // namespace mapd::service

#endif  // MAPD_SERVICE_MAP_FORWARDER_H_
