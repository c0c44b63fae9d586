// The calls a gRPC server is handling, counted by an interceptor, so that a
// shutdown can wait for them and only them. grpc::Server::Shutdown(deadline)
// also waits until every client connection has closed, and a connected
// client's idle channel (a robot between streams, a dashboard) closes only
// after about 5 s, or never before the deadline: every stop with robots
// connected took shutdown_grace_s. MapServer::Shutdown waits for the calls
// here, then gives gRPC a short deadline that ends the idle connections.
//
// Thread-safe. Must outlive the server whose interceptor uses it.
#ifndef MAPD_SERVICE_CALLS_IN_PROGRESS_H_
#define MAPD_SERVICE_CALLS_IN_PROGRESS_H_

#include <grpcpp/support/server_interceptor.h>

#include <atomic>
#include <chrono>
#include <cstdint>
#include <memory>

namespace mapd::service {

class CallsInProgress {
 public:
  // For grpc::ServerBuilder::experimental().SetInterceptorCreators. A call
  // counts from its start until gRPC destroys it (status sent, or cancelled).
  // grpc.health.v1.Health/Watch is not counted: a health watch lasts as long
  // as its client and has nothing to finish.
  std::unique_ptr<grpc::experimental::ServerInterceptorFactoryInterface> InterceptorFactory();

  int64_t count() const { return count_.load(); }
  // Waits (polling every 5 ms) until no call is in progress or `deadline`;
  // true if none is.
  bool WaitUntilNone(std::chrono::steady_clock::time_point deadline) const;

 private:
  std::atomic<int64_t> count_{0};
};

}  // namespace mapd::service

#endif  // MAPD_SERVICE_CALLS_IN_PROGRESS_H_
