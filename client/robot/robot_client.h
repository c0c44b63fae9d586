// RobotClient: how a robot streams observation batches to mapd.
//
// One Ingest stream per client. Send() writes a batch at once and returns
// without waiting for its acknowledgement (pipelining); the client keeps every
// batch until the server's IngestAck for it arrives. When the stream fails the
// client reconnects (with backoff) and resends, in the original order, every
// batch not yet acknowledged. Resending is safe: the server answers a batch it
// already stored with DUPLICATE and applies nothing twice.
//
// Acks are matched to batches by (session_id, seq), so those must be unique
// among the batches a client has in flight.
//
// Threading: Send(), WaitForAcks(), Finish() and the accessors may be called
// from any thread. One internal reader thread collects the acks and owns
// reconnection. A stream refused UNAUTHENTICATED or PERMISSION_DENIED is
// final: the client gives up at once (retrying cannot help).
#ifndef MAPD_CLIENT_ROBOT_ROBOT_CLIENT_H_
#define MAPD_CLIENT_ROBOT_ROBOT_CLIENT_H_

#include <grpcpp/grpcpp.h>

#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "mapserver/v1/map_service.grpc.pb.h"

namespace mapd::robot {

// How quickly a restarted server is found again also depends on the channel's
// own reconnect backoff (GRPC_ARG_INITIAL/MAX_RECONNECT_BACKOFF_MS; gRPC's
// default grows to 120 s): mapctl sets it to 0.2..2 s.
struct RobotClientOptions {
  // Give up when streams keep failing for this long with no ack in between.
  std::chrono::milliseconds give_up_after{30000};
  std::chrono::milliseconds initial_backoff{100};  // pause before a reconnect, doubled each time
  std::chrono::milliseconds max_backoff{2000};
  // Send() blocks while this many batches are unacknowledged (back-pressure).
  size_t max_unacknowledged = 1000;
  // Sent as `authorization: Bearer <token>` on every stream (docs/security.md);
  // empty: none (the open mode, or a client certificate on the channel).
  std::string token;
  // The map the batches are for, when mapd serves several (the stream's
  // mapd-map-id metadata); empty: the server's default map. With a map
  // other than "default" the client first asks the server (ListMaps) and
  // gives up when it does not know maps (FAILED_PRECONDITION: a mapd from
  // before maps would store them in its only map) or that map (NOT_FOUND).
  std::string map_id;
  // Several mapd on one database (docs/scale-out.md): makes a channel to
  // another instance (same credentials as the first). With it the client
  // follows redirects (a stream refused with the owner's address in the
  // trailing metadata mapd-map-owner goes there next) and, when the
  // current server cannot be reached, tries `addresses` in turn. Null: one
  // server, the channel given.
  std::function<std::shared_ptr<grpc::Channel>(const std::string& address)> connect;
  std::vector<std::string> addresses;  // host:port of the other instances
};

// What the server answered, over the client's lifetime.
struct IngestCounts {
  uint64_t sent = 0;        // distinct batches passed to Send()
  uint64_t stored = 0;      // acknowledged STORED
  uint64_t duplicate = 0;   // acknowledged DUPLICATE (sent before, e.g. resent after a drop)
  uint64_t rejected = 0;    // acknowledged REJECTED (final: the batch is wrong)
  uint64_t reconnects = 0;  // streams opened after the first one
  uint64_t redirects = 0;   // moves to another mapd (a redirect, or the current one unreachable)
};

// One batch the server refused.
struct Rejection {
  std::string session_id;
  uint64_t seq = 0;
  grpc::StatusCode code = grpc::StatusCode::UNKNOWN;
  std::string message;  // names the offending field, e.g. "lines[3].a.x is NaN"
};

// Arguments for a robot's channel (mapctl uses them): a restarted server is
// found again within 2 s (gRPC's reconnect backoff grows to 120 s by
// default), and a dead or frozen one is noticed within about 8 s (keepalive
// pings every 5 s while a stream is open, answered within 3 s; mapd permits
// pings that often, limits.min_client_ping_interval_s). The client then
// resends to it, or with RobotClientOptions::connect fails over.
grpc::ChannelArguments RobotChannelArguments();

// Whether the server behind `stub` serves `map`, asked with ListMaps on
// `context`: OK; FAILED_PRECONDITION when it knows no maps (a mapd from before
// maps ignores a map's name and would store the batches in its only map);
// NOT_FOUND naming the maps it serves; or the call's error.
grpc::Status CheckMapServed(mapserver::v1::MapService::Stub* stub, grpc::ClientContext* context,
                            const std::string& map);

class RobotClient {
 public:
  explicit RobotClient(std::shared_ptr<grpc::Channel> channel, RobotClientOptions options = {});
  // Cancels the stream (unacknowledged batches stay unacknowledged) and joins
  // the reader thread. Call Finish() first for a clean end.
  ~RobotClient();

  RobotClient(const RobotClient&) = delete;
  RobotClient& operator=(const RobotClient&) = delete;

  // Writes `batch` to the stream and keeps it until it is acknowledged. Does not
  // wait for the ack. May block while gRPC flow control holds the stream.
  // REQUIRES: Finish() has not been called.
  void Send(mapserver::v1::ObservationBatch batch);

  // Blocks until every batch sent so far has a final ack, the client has given
  // up, or `timeout` has passed. True when nothing is left unacknowledged.
  bool WaitForAcks(std::chrono::milliseconds timeout);

  // Waits for the acks (as WaitForAcks), closes the stream and joins the
  // reader. OK when every batch was acknowledged (rejected ones included: see
  // counts()); otherwise the reason, e.g. UNAVAILABLE with the server's message
  // when it could not be reached, DEADLINE_EXCEEDED when acks were missing.
  grpc::Status Finish(std::chrono::milliseconds timeout);

  IngestCounts counts() const;
  std::vector<Rejection> rejections() const;
  size_t unacknowledged() const;

 private:
  using Key = std::pair<std::string, uint64_t>;  // (session_id, seq)
  using Stream =
      grpc::ClientReaderWriter<mapserver::v1::ObservationBatch, mapserver::v1::IngestAck>;

  void ReaderLoop();
  // CheckMapServed(options_.map_id), cancellable like a stream.
  grpc::Status CheckMap();
  // Opens a stream and writes every pending batch to it. REQUIRES: write_mu_ held.
  void OpenStreamLocked();
  // Counts a final answer (true) or keeps the batch pending (false).
  bool HandleAck(const mapserver::v1::IngestAck& ack);
  // Asks the channel to connect and waits until it is ready, `deadline` or Stop.
  void WaitForChannel(std::chrono::steady_clock::time_point deadline);
  // Where the reader goes after a failed stream: the redirect's address, or
  // with the current server unreachable the next of options_.addresses.
  // Returns true when it moved. Reader thread only.
  bool MoveAfterFailure(const grpc::Status& status, const std::string& redirect,
                        std::chrono::steady_clock::time_point give_up_at);
  // Points channel_ and stub_ at `address` (options_.connect). Reader thread only.
  void ConnectTo(const std::string& address);
  // Ends the reader as soon as possible: stops waiting, cancels the stream.
  void CancelLocked();  // REQUIRES: mu_ held

  // Replaced by the reader only, between streams, under write_mu_.
  std::shared_ptr<grpc::Channel> channel_;
  std::unique_ptr<mapserver::v1::MapService::Stub> stub_;
  std::shared_ptr<grpc::Channel> first_channel_;  // the one given
  size_t next_address_ = 0;                       // into options_.addresses, then the first
  const RobotClientOptions options_;

  // Lock order: write_mu_ before mu_.
  std::mutex write_mu_;  // serialises writes to and replacement of the stream
  std::unique_ptr<grpc::ClientContext> context_;  // GUARDED_BY(write_mu_)
  std::unique_ptr<Stream> stream_;                // GUARDED_BY(write_mu_)
  bool half_closed_ = false;                      // GUARDED_BY(write_mu_)

  mutable std::mutex mu_;
  std::condition_variable cv_;
  // Unacknowledged batches in sending order (key: order of first Send()).
  std::map<uint64_t, mapserver::v1::ObservationBatch> pending_;  // GUARDED_BY(mu_)
  std::map<Key, uint64_t> order_of_;                             // GUARDED_BY(mu_)
  uint64_t next_order_ = 0;                                      // GUARDED_BY(mu_)
  IngestCounts counts_;                                          // GUARDED_BY(mu_)
  std::vector<Rejection> rejections_;                            // GUARDED_BY(mu_)
  bool closing_ = false;      // Finish() called                     // GUARDED_BY(mu_)
  bool stopping_ = false;     // destructor: stop at once            // GUARDED_BY(mu_)
  bool gave_up_ = false;      // GUARDED_BY(mu_)
  bool reader_done_ = false;  // GUARDED_BY(mu_)
  grpc::Status last_error_;   // GUARDED_BY(mu_)
  // The current stream's context, for cancelling without write_mu_.
  grpc::ClientContext* cancel_target_ = nullptr;  // GUARDED_BY(mu_)

  std::thread reader_;
};

}  // namespace mapd::robot

#endif  // MAPD_CLIENT_ROBOT_ROBOT_CLIENT_H_
