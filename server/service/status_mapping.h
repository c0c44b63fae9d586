// The ONE place where an internal Status becomes a grpc::Status.
#ifndef MAPD_SERVICE_STATUS_MAPPING_H_
#define MAPD_SERVICE_STATUS_MAPPING_H_

#include <grpcpp/support/status.h>

#include "common/status.h"

namespace mapd::service {

grpc::StatusCode ToGrpcCode(StatusCode code);
grpc::Status ToGrpcStatus(const Status& status);

}  // namespace mapd::service

#endif  // MAPD_SERVICE_STATUS_MAPPING_H_
