// Streams relayed to a map's owner (map_forwarder.h): an Ingest stream or a
// submap upload that reached an instance which does not serve its map, for
// clients that know one address and do not follow redirects. Messages go
// through one at a time each way (a read is started only once the previous
// message was written on), so a relay holds at most one message per
// direction and the owner's flow control reaches the client. The owner's
// status (and redirect metadata) ends the caller's stream.
//
// Each relay is owned by gRPC and deletes itself once both its halves (the
// caller's call and the call to the owner) are done. It holds its place under
// this instance's limits.max_streams (`slot`) until then: a relay costs the
// relaying instance a stream as much as a local one does.
#ifndef MAPD_SERVICE_STREAM_RELAY_H_
#define MAPD_SERVICE_STREAM_RELAY_H_

#include <grpcpp/grpcpp.h>

#include <memory>
#include <string>

#include "mapserver/v1/map_service.grpc.pb.h"
#include "service/map_forwarder.h"
#include "service/stream_limiter.h"

namespace mapd::service {

// Ingest (raw messages: the owner parses and acknowledges them).
grpc::ServerBidiReactor<grpc::ByteBuffer, grpc::ByteBuffer>* RelayIngest(
    grpc::CallbackServerContext* context, MapForwarder* forwarder, const std::string& owner,
    StreamSlot slot);

// UploadSubmap; `response` is filled with the owner's answer.
grpc::ServerReadReactor<mapserver::v1::UploadSubmapRequest>* RelayUpload(
    grpc::CallbackServerContext* context, mapserver::v1::SubmapInfo* response,
    MapForwarder* forwarder, const std::string& owner, StreamSlot slot);

}  // namespace mapd::service

#endif  // MAPD_SERVICE_STREAM_RELAY_H_
