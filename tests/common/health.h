// grpc.health.v1.Health/Check from a test, through gRPC's generic stub
// (Debian ships the health service, not client stubs for it). Header-only.
#ifndef MAPD_TESTS_COMMON_HEALTH_H_
#define MAPD_TESTS_COMMON_HEALTH_H_

#include <chrono>
#include <future>
#include <memory>
#include <string>
#include <vector>

#include <grpcpp/generic/generic_stub.h>
#include <grpcpp/grpcpp.h>

namespace mapd::testing {

enum class Health { kError = -1, kUnknown = 0, kServing = 1, kNotServing = 2 };

// The server's overall status (service "") over `channel`, or kError if the
// call failed (within `deadline`).
inline Health CheckHealth(const std::shared_ptr<grpc::Channel>& channel,
                          std::chrono::milliseconds deadline = std::chrono::seconds(5)) {
  grpc::GenericStub stub(channel);
  grpc::ClientContext ctx;
  ctx.set_deadline(std::chrono::system_clock::now() + deadline);
  grpc::Slice empty(std::string{});  // HealthCheckRequest{service: ""} encodes to no bytes
  const grpc::ByteBuffer request(&empty, 1);
  grpc::ByteBuffer response;
  std::promise<grpc::Status> done;
  stub.UnaryCall(&ctx, "/grpc.health.v1.Health/Check", grpc::StubOptions(), &request, &response,
                 [&done](grpc::Status s) { done.set_value(s); });
  if (!done.get_future().get().ok()) return Health::kError;
  std::vector<grpc::Slice> slices;
  if (!response.Dump(&slices).ok()) return Health::kError;
  std::string bytes;
  for (const grpc::Slice& s : slices) bytes.append(reinterpret_cast<const char*>(s.begin()), s.size());
  // HealthCheckResponse{status = 1}: field 1, varint; proto3 omits 0 (UNKNOWN).
  if (bytes.empty()) return Health::kUnknown;
  if (bytes.size() == 2 && bytes[0] == 0x08) return static_cast<Health>(bytes[1]);
  return Health::kError;
}

// The same on a channel of its own to `address` (plaintext).
inline Health CheckHealth(const std::string& address) {
  return CheckHealth(grpc::CreateChannel(address, grpc::InsecureChannelCredentials()));
}

}  // namespace mapd::testing

#endif  // MAPD_TESTS_COMMON_HEALTH_H_
