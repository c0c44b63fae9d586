// The ONE place where an internal Status becomes a grpc::Status.
#ifndef MAPD_SERVICE_STATUS_MAPPING_H_
#define MAPD_SERVICE_STATUS_MAPPING_H_

#include <grpcpp/support/status.h>

#include <string>

#include "common/status.h"

namespace mapd::service {

grpc::StatusCode ToGrpcCode(StatusCode code);
grpc::Status ToGrpcStatus(const Status& status);

// INVALID_ARGUMENT with `message` (which names the field).
grpc::Status InvalidArgument(const std::string& message);
// UNAVAILABLE while mapd drains for shutdown.
grpc::Status ShuttingDown();

// Returns the mapped status from a handler when `expr` (a Status) fails.
#define MAPD_RETURN_IF_ERROR_GRPC(expr)                                                 \
  do {                                                                                  \
    if (::mapd::Status _s = (expr); !_s.ok()) return ::mapd::service::ToGrpcStatus(_s); \
  } while (0)

}  // namespace mapd::service

#endif  // MAPD_SERVICE_STATUS_MAPPING_H_
