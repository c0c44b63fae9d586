// A stream answered at once with an error (limits, shutdown, recovery): no
// reads, no per-stream state beyond this object. Owned by gRPC.
#ifndef MAPD_SERVICE_REFUSED_STREAM_H_
#define MAPD_SERVICE_REFUSED_STREAM_H_

#include <grpcpp/grpcpp.h>

#include <utility>

namespace mapd::service {

// Reactor: grpc::ServerBidiReactor<...> or grpc::ServerReadReactor<...>.
template <class Reactor>
class RefusedStream : public Reactor {
 public:
  explicit RefusedStream(grpc::Status why) { this->Finish(std::move(why)); }
  void OnDone() override { delete this; }
};

}  // namespace mapd::service

#endif  // MAPD_SERVICE_REFUSED_STREAM_H_
