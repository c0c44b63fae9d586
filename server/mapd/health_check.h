// grpc.health.v1.Health/Check (the server's overall status, service "", or
// one map's, "map/<id>")
// through gRPC's generic stub: Debian ships gRPC's health service but no
// client stubs for it, so the two-byte messages are encoded here. Used by
// mapd-health and by the tests. Header-only, gRPC only.
#ifndef MAPD_MAPD_HEALTH_CHECK_H_
#define MAPD_MAPD_HEALTH_CHECK_H_

#include <grpcpp/generic/generic_stub.h>
#include <grpcpp/grpcpp.h>

#include <chrono>
#include <future>
#include <memory>
#include <string>
#include <vector>

namespace mapd {

// HealthCheckResponse.ServingStatus.
enum class ServingStatus { kUnknown = 0, kServing = 1, kNotServing = 2 };

inline const char* ServingStatusName(ServingStatus s) {
  switch (s) {
    case ServingStatus::kServing:
      return "SERVING";
    case ServingStatus::kNotServing:
      return "NOT_SERVING";
    case ServingStatus::kUnknown:
      break;
  }
  return "UNKNOWN";
}

// Asks `channel` within `deadline` about `service` (under 128 bytes); the
// call's status (NOT_FOUND for a service the server does not know), and on
// success the server's answer in *status (UNKNOWN for an answer it cannot read).
inline grpc::Status CheckHealth(const std::shared_ptr<grpc::Channel>& channel,
                                std::chrono::milliseconds deadline, ServingStatus* status,
                                const std::string& service = "") {
  grpc::GenericStub stub(channel);
  grpc::ClientContext ctx;
  ctx.set_deadline(std::chrono::system_clock::now() + deadline);
  // HealthCheckRequest{service}: field 1, length-delimited; "" encodes to no bytes.
  std::string encoded;
  if (!service.empty() && service.size() < 128) {
    encoded = std::string{'\x0a', static_cast<char>(service.size())} + service;
  }
  grpc::Slice slice(encoded);
  const grpc::ByteBuffer request(&slice, 1);
  grpc::ByteBuffer response;
  std::promise<grpc::Status> done;
  stub.UnaryCall(&ctx, "/grpc.health.v1.Health/Check", grpc::StubOptions(), &request, &response,
                 [&done](grpc::Status s) { done.set_value(s); });
  const grpc::Status call = done.get_future().get();
  *status = ServingStatus::kUnknown;
  if (!call.ok()) return call;
  std::vector<grpc::Slice> slices;
  if (!response.Dump(&slices).ok()) return call;
  std::string bytes;
  for (const grpc::Slice& s : slices)
    bytes.append(reinterpret_cast<const char*>(s.begin()), s.size());
  // HealthCheckResponse{status}: field 1, varint; proto3 omits 0 (UNKNOWN).
  if (bytes.size() == 2 && bytes[0] == 0x08 && bytes[1] >= 0 && bytes[1] <= 2) {
    *status = static_cast<ServingStatus>(bytes[1]);
  }
  return call;
}

}  // namespace mapd

#endif  // MAPD_MAPD_HEALTH_CHECK_H_
