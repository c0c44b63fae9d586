// The Ingest RPC: one reactor per robot stream (gRPC callback API).
//
// Batches are read continuously and handed to the Core; acknowledgements are
// written as the writer commits them, so a robot can keep up to
// `max_in_flight` batches in flight on one stream (reading pauses above that:
// flow control rather than unbounded memory). A refused batch gets a REJECTED
// ack and the stream goes on; so is a batch for a robot id the caller may not
// write (PERMISSION_DENIED; the first such batch of a stream is audited, and
// its ack waits for that audit row to be committed). The caller's role was
// checked before the stream was opened (MapServiceImpl::Ingest).
//
// The method is registered raw (ByteBuffer in and out) and the reactor parses
// each message itself: with the typed callback API a message that does not
// parse looks exactly like a half-close (OnReadDone(false)) and the stream
// would end OK with the rest silently unacknowledged. Here a malformed message
// ends the stream with INVALID_ARGUMENT naming its index (after the batches
// before it are acknowledged), and a log line.
//
// At shutdown (IngestStreams::DrainAll) every stream ends as soon as its
// batches in flight are acknowledged, with UNAVAILABLE: a robot that keeps
// its stream open but sends nothing (parked) must not hold mapd's stop for
// shutdown_grace_s, and a batch that arrives meanwhile is refused, so the
// robot resends it after reconnecting.
#ifndef MAPD_SERVICE_INGEST_REACTOR_H_
#define MAPD_SERVICE_INGEST_REACTOR_H_

#include <grpcpp/grpcpp.h>

#include <atomic>
#include <deque>
#include <mutex>
#include <string>
#include <unordered_set>

#include "mapserver/v1/map_service.pb.h"
#include "service/access_control.h"
#include "service/core.h"
#include "service/ingest_batch.h"
#include "service/options.h"
#include "service/stream_limiter.h"

namespace mapd::service {

class IngestReactor;

// The open Ingest streams of a server, so that a shutdown can end them.
// Thread-safe.
class IngestStreams {
 public:
  // From now on every open stream, and every one opened later, ends once its
  // batches in flight are acknowledged.
  void DrainAll();
  bool draining() const { return draining_.load(); }

 private:
  friend class IngestReactor;
  void Add(IngestReactor* stream);
  void Remove(IngestReactor* stream);

  std::atomic<bool> draining_{false};
  std::mutex mu_;                            // taken before an IngestReactor's, never after
  std::unordered_set<IngestReactor*> open_;  // GUARDED_BY(mu_)
};

// Owned by gRPC; deletes itself in OnDone().
class IngestReactor : public grpc::ServerBidiReactor<grpc::ByteBuffer, grpc::ByteBuffer> {
 public:
  IngestReactor(grpc::CallbackServerContext* context, Core* core, const IngestOptions* options,
                IngestStreams* streams, AccessControl* access, Principal caller, StreamSlot slot,
                CallHold hold = nullptr);

  void OnReadDone(bool ok) override;
  void OnWriteDone(bool ok) override;
  void OnCancel() override;
  void OnDone() override;

  // Shutdown: finish as soon as nothing is in flight (IngestStreams::DrainAll).
  void Drain();

 private:
  void Complete(mapserver::v1::IngestAck ack);  // a batch's outcome is final
  void StartNextWriteLocked();                  // REQUIRES: mu_ held
  void MaybeReadLocked();                       // REQUIRES: mu_ held
  void MaybeFinishLocked();                     // REQUIRES: mu_ held

  const CallHold hold_;  // first: released last, after every member that uses the map
  Core* const core_;
  const IngestOptions* const options_;
  IngestStreams* const streams_;
  const std::string peer_;
  AccessControl* const access_;
  const Principal caller_;

  StreamSlot slot_;  // our place under limits.max_streams

  std::mutex mu_;
  grpc::ByteBuffer read_buffer_;             // the buffer of the outstanding read
  mapserver::v1::ObservationBatch request_;  // read_buffer_ parsed
  grpc::ByteBuffer write_buffer_;            // the buffer of the outstanding write
  uint64_t messages_read_ = 0;               // GUARDED_BY(mu_), index of the next message
  grpc::Status end_status_;  // GUARDED_BY(mu_), what Finish reports (a malformed message)
  std::deque<mapserver::v1::IngestAck> acks_;  // GUARDED_BY(mu_), waiting to be written
  uint32_t in_flight_ = 0;     // GUARDED_BY(mu_), batches handed out, outcome pending
  bool read_pending_ = false;  // GUARDED_BY(mu_), a read is outstanding in gRPC
  bool processing_ = false;    // GUARDED_BY(mu_), OnReadDone is handling request_
  bool writing_ = false;       // GUARDED_BY(mu_)
  bool read_closed_ = false;   // GUARDED_BY(mu_), the client half-closed or the call ended
  bool broken_ = false;        // GUARDED_BY(mu_), a write failed: the client is gone
  bool finished_ = false;      // GUARDED_BY(mu_)
  std::string robot_;          // for logs, from the first batch
  uint64_t stored_ = 0, duplicates_ = 0,
           rejected_ = 0;  // GUARDED_BY(mu_), for the closing log line
  uint64_t denied_ = 0;    // batches refused PERMISSION_DENIED; reader thread only
};

}  // namespace mapd::service

#endif  // MAPD_SERVICE_INGEST_REACTOR_H_
