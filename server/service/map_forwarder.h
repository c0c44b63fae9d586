// Forwarding (docs/scale-out.md, "Redirects and clients"): with several mapd
// on one database, a call for a map another instance serves is relayed to
// that instance and its answer returned, for clients that know one address
// and do not follow redirects (grpcurl, scripts, clients from before
// redirects). Unary and server-streaming calls are forwarded; a stream of
// batches or an upload is redirected (RobotClient follows redirects, and a
// relayed stream would double the load of the busiest path).
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

#include <grpcpp/grpcpp.h>

#include <map>
#include <memory>
#include <mutex>
#include <string>

#include "mapserver/v1/map_service.grpc.pb.h"

namespace mapd::service {

inline constexpr char kForwardedMetadata[] = "mapd-forwarded-by";

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

  // Whether `caller`'s call may be forwarded: not forwarded already, and
  // not known by a client certificate alone.
  static bool MayForward(const grpc::ServerContextBase& caller);
  // A stub for the mapd at `address` (host:port); channels are kept.
  mapserver::v1::MapService::Stub* StubTo(const std::string& address);
  // The forwarded call's context: `caller`'s deadline, token and map.
  std::unique_ptr<grpc::ClientContext> ContextFor(const grpc::ServerContextBase& caller) const;
  // The owner's redirect metadata (a map that moved meanwhile), copied
  // back to the caller.
  static void CopyRedirect(const grpc::ClientContext& from, grpc::ServerContextBase& to);

 private:
  const std::shared_ptr<grpc::ChannelCredentials> credentials_;
  const std::string forwarder_;
  const int max_message_bytes_;
  std::mutex mu_;
  std::map<std::string, std::unique_ptr<mapserver::v1::MapService::Stub>>
      stubs_;  // GUARDED_BY(mu_)
};

}  // namespace mapd::service

#endif  // MAPD_SERVICE_MAP_FORWARDER_H_
