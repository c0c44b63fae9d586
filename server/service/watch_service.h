// WatchFeatureMap (the proto has the contract): one watch on a synchronous
// gRPC thread. It subscribes to the core's WatchHub, sends the full filtered
// map or the changes since the client's version, then each change the fuser
// publishes, filtered for this client: a feature that enters the filter is
// added, one that leaves it removed. A watcher that fell behind (its queue
// overflowed) gets a resync. The call ends when the client cancels, or with
// UNAVAILABLE at shutdown (WatchHub::Close).
#ifndef MAPD_SERVICE_WATCH_SERVICE_H_
#define MAPD_SERVICE_WATCH_SERVICE_H_

#include <grpcpp/grpcpp.h>
#include <grpcpp/support/sync_stream.h>

#include "common/status.h"
#include "mapserver/v1/map_service.pb.h"
#include "service/core.h"
#include "service/feature_filter.h"

namespace mapd::service {

// Checks a request (INVALID_ARGUMENT naming the field): the bbox, the kind,
// the robot id, and that since_map_version is not newer than `map_version`.
Status ParseWatchRequest(const mapserver::v1::WatchFeatureMapRequest& request, uint64_t map_version,
                         FeatureFilter* filter);

// Serves one admitted watch until it ends. REQUIRES: the core is ready.
grpc::Status ServeWatch(Core* core, grpc::ServerContext* context,
                        const mapserver::v1::WatchFeatureMapRequest& request,
                        const FeatureFilter& filter,
                        grpc::ServerWriter<mapserver::v1::FeatureMapDelta>* writer);

}  // namespace mapd::service

#endif  // MAPD_SERVICE_WATCH_SERVICE_H_
