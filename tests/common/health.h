// grpc.health.v1.Health/Check from a test (mapd/health_check.h, which
// mapd-health uses), with kError for a failed call. Header-only.
#ifndef MAPD_TESTS_COMMON_HEALTH_H_
#define MAPD_TESTS_COMMON_HEALTH_H_

#include <grpcpp/grpcpp.h>

#include <chrono>
#include <memory>
#include <string>

#include "mapd/health_check.h"

namespace mapd::testing {

enum class Health { kError = -1, kUnknown = 0, kServing = 1, kNotServing = 2 };

// The server's overall status (service "") over `channel`, or kError if the
// call failed (within `deadline`).
inline Health CheckHealth(const std::shared_ptr<grpc::Channel>& channel,
                          std::chrono::milliseconds deadline = std::chrono::seconds(5),
                          const std::string& service = "") {
  ServingStatus serving = ServingStatus::kUnknown;
  if (!mapd::CheckHealth(channel, deadline, &serving, service).ok()) return Health::kError;
  return static_cast<Health>(serving);
}

// The same on a channel of its own to `address` (plaintext).
inline Health CheckHealth(const std::string& address) {
  return CheckHealth(grpc::CreateChannel(address, grpc::InsecureChannelCredentials()));
}

}  // namespace mapd::testing

#endif  // MAPD_TESTS_COMMON_HEALTH_H_
