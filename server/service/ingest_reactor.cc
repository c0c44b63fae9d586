#include "service/ingest_reactor.h"

#include <grpcpp/impl/codegen/proto_utils.h>
#include <grpcpp/support/proto_buffer_reader.h>
#include <grpcpp/support/proto_buffer_writer.h>

#include "service/log.h"
#include "service/rpc_metrics.h"
#include "service/status_mapping.h"

namespace mapd::service {

namespace pb = mapserver::v1;

IngestReactor::IngestReactor(grpc::CallbackServerContext* context, Core* core,
                             const IngestOptions* options, IngestStreams* streams,
                             AccessControl* access, Principal caller, StreamSlot slot,
                             CallHold hold)
    : hold_(std::move(hold)),
      core_(core),
      options_(options),
      streams_(streams),
      peer_(context->peer()),
      access_(access),
      caller_(std::move(caller)),
      slot_(std::move(slot)) {
  streams_->Add(this);
  std::lock_guard<std::mutex> lock(mu_);
  read_pending_ = true;
  StartRead(&read_buffer_);
  MaybeFinishLocked();  // opened after a drain began: ends at once
}

void IngestReactor::OnReadDone(bool ok) {
  {
    std::lock_guard<std::mutex> lock(mu_);
    read_pending_ = false;
    // Finished by a drain while this read was outstanding: a batch that came
    // in meanwhile is dropped unacknowledged (the robot resends it).
    if (finished_) return;
    if (!ok) {
      read_closed_ = true;
      MaybeFinishLocked();
      return;
    }
    processing_ = true;
    const uint64_t index = messages_read_++;
    request_.Clear();
    grpc::Status parsed =
        grpc::SerializationTraits<pb::ObservationBatch>::Deserialize(&read_buffer_, &request_);
    if (!parsed.ok()) {
      // Stop reading; what was read before is acknowledged, then the stream ends.
      processing_ = false;
      read_closed_ = true;
      end_status_ = grpc::Status(grpc::StatusCode::INVALID_ARGUMENT,
                                 "message " + std::to_string(index) +
                                     " of the stream (0-based) is not a valid ObservationBatch (" +
                                     parsed.error_message() +
                                     "); the stream ends, the batches before it are "
                                     "acknowledged, nothing after it was read");
      Log(LogLevel::kWarn, "ingest_malformed",
          {{"robot", robot_},
           {"peer", peer_},
           {"message", std::to_string(index)},
           {"error", parsed.error_message()}});
      MaybeFinishLocked();
      return;
    }
    ++in_flight_;
    if (robot_.empty()) robot_ = request_.robot_id().substr(0, 128);
  }
  // processing_ stays true while request_ is being handled, so that no one
  // starts another read into it.
  pb::IngestAck ack;
  ack.set_session_id(request_.session_id());
  ack.set_seq(request_.seq());
  if (streams_->draining()) {
    ack.set_result(pb::IngestAck::REJECTED);
    ack.set_code(grpc::StatusCode::UNAVAILABLE);
    ack.set_message("mapd is shutting down; reconnect and resend unacknowledged batches");
    Complete(std::move(ack));
  } else if (!request_.map_id().empty() && request_.map_id() != options_->map_id) {
    // One stream, one map: the stream goes on (a client bug, not an attack).
    ack.set_result(pb::IngestAck::REJECTED);
    ack.set_code(grpc::StatusCode::INVALID_ARGUMENT);
    ack.set_message("map_id is '" + request_.map_id().substr(0, 128) +
                    "' but this stream writes map '" + options_->map_id +
                    "'; open one Ingest stream per map, naming it in the mapd-map-id metadata");
    Complete(std::move(ack));
  } else if (StatusOr<IngestBatch> batch = ValidateBatch(request_, options_->limits); !batch.ok()) {
    // Validated before the authorization, so that a refusal's log line and
    // audit row only ever name well-formed ids (issue 43: a robot id with a
    // newline forged an audit row).
    Log(LogLevel::kWarn, "ingest_rejected",
        {{"robot", request_.robot_id().substr(0, 64)},
         {"session", request_.session_id().substr(0, 64)},
         {"seq", std::to_string(request_.seq())},
         {"peer", peer_},
         {"error", batch.status().ToString()}});
    ack.set_result(pb::IngestAck::REJECTED);
    ack.set_code(ToGrpcCode(batch.status().code()));
    ack.set_message(batch.status().message());
    Complete(std::move(ack));
  } else if (Status may = Authorize(caller_, Permission::kWrite, "Ingest", batch->robot);
             !may.ok()) {
    ack.set_result(pb::IngestAck::REJECTED);
    ack.set_code(ToGrpcCode(may.code()));
    ack.set_message(may.message());
    if (denied_++ == 0) {
      Log(LogLevel::kWarn, "permission_denied",
          {{"who", caller_.name}, {"action", "Ingest"}, {"robot", batch->robot}, {"peer", peer_}});
      access_->AuditDeniedAsync(
          AccessControl::Entry(caller_, "Ingest",
                               "robot " + batch->robot + " session " + request_.session_id(),
                               "denied: " + may.message()),
          [this, ack]() mutable { Complete(std::move(ack)); });
    } else {
      Complete(std::move(ack));
    }
  } else {
    core_->Submit(std::move(batch).value(), [this, ack](const BatchOutcome& outcome) mutable {
      switch (outcome.kind) {
        case BatchOutcome::Kind::kStored:
          ack.set_result(pb::IngestAck::STORED);
          break;
        case BatchOutcome::Kind::kDuplicate:
          ack.set_result(pb::IngestAck::DUPLICATE);
          break;
        case BatchOutcome::Kind::kRejected:
          ack.set_result(pb::IngestAck::REJECTED);
          ack.set_code(ToGrpcCode(outcome.status.code()));
          ack.set_message(outcome.status.message());
          break;
      }
      Complete(std::move(ack));
    });
  }
  std::lock_guard<std::mutex> lock(mu_);
  processing_ = false;
  MaybeReadLocked();
  MaybeFinishLocked();
}

void IngestReactor::Complete(pb::IngestAck ack) {
  std::lock_guard<std::mutex> lock(mu_);
  --in_flight_;
  switch (ack.result()) {
    case pb::IngestAck::STORED:
      ++stored_;
      break;
    case pb::IngestAck::DUPLICATE:
      ++duplicates_;
      break;
    default:
      ++rejected_;
      RpcMetrics::Default().RecordRejectedBatch(static_cast<grpc::StatusCode>(ack.code()));
  }
  if (!broken_) acks_.push_back(std::move(ack));
  if (!writing_) StartNextWriteLocked();
  MaybeReadLocked();
  MaybeFinishLocked();
}

void IngestReactor::StartNextWriteLocked() {
  if (acks_.empty() || broken_) return;
  bool own_buffer = false;
  write_buffer_.Clear();
  grpc::Status s = grpc::SerializationTraits<pb::IngestAck>::Serialize(acks_.front(),
                                                                       &write_buffer_, &own_buffer);
  acks_.pop_front();
  if (!s.ok()) {  // an ack always serialises; if not, the client cannot be told
    broken_ = true;
    acks_.clear();
    return;
  }
  writing_ = true;
  // While more acks are queued, let gRPC coalesce them into fewer frames.
  grpc::WriteOptions options;
  if (!acks_.empty()) options.set_buffer_hint();
  StartWrite(&write_buffer_, options);
}

void IngestReactor::OnWriteDone(bool ok) {
  std::lock_guard<std::mutex> lock(mu_);
  writing_ = false;
  if (!ok) {
    broken_ = true;
    acks_.clear();
  }
  StartNextWriteLocked();
  MaybeFinishLocked();
}

void IngestReactor::MaybeReadLocked() {
  if (read_pending_ || processing_ || read_closed_ || finished_ || streams_->draining() ||
      in_flight_ >= options_->max_in_flight)
    return;
  read_pending_ = true;
  StartRead(&read_buffer_);
}

void IngestReactor::Drain() {
  std::lock_guard<std::mutex> lock(mu_);
  MaybeFinishLocked();
}

void IngestReactor::OnCancel() {
  std::lock_guard<std::mutex> lock(mu_);
  Log(LogLevel::kDebug, "ingest_cancelled", {{"robot", robot_}, {"peer", peer_}});
  MaybeFinishLocked();
}

void IngestReactor::MaybeFinishLocked() {
  // Finish only when no callback of MapCore can still reach this reactor and
  // every ack is written; and, unless mapd is stopping, once the client has
  // half-closed. A read still outstanding then completes with ok = false.
  if (finished_ || processing_ || in_flight_ > 0 || writing_ || !acks_.empty()) return;
  const bool draining = streams_->draining();
  if (!draining && !read_closed_) return;
  if (!read_closed_ && end_status_.ok()) {
    end_status_ = grpc::Status(grpc::StatusCode::UNAVAILABLE,
                               "mapd is shutting down; reconnect and resend unacknowledged "
                               "batches");
  }
  finished_ = true;
  Log(LogLevel::kInfo, "ingest_stream_closed",
      {{"robot", robot_},
       {"peer", peer_},
       {"stored", std::to_string(stored_)},
       {"duplicate", std::to_string(duplicates_)},
       {"rejected", std::to_string(rejected_)},
       {"client_gone", broken_ ? "true" : "false"},
       {"shutdown", draining ? "true" : "false"}});
  slot_.Release();  // before the client sees the status (its next stream must find the place)
  Finish(end_status_);
}

void IngestReactor::OnDone() {
  streams_->Remove(this);
  // Finish() is called with mu_ held; gRPC may run OnDone on another thread
  // before that caller has let go of it.
  { std::lock_guard<std::mutex> lock(mu_); }
  delete this;
}

void IngestStreams::Add(IngestReactor* stream) {
  std::lock_guard<std::mutex> lock(mu_);
  open_.insert(stream);
}

void IngestStreams::Remove(IngestReactor* stream) {
  std::lock_guard<std::mutex> lock(mu_);
  open_.erase(stream);
}

void IngestStreams::DrainAll() {
  // Under mu_: a stream cannot be deleted (OnDone) while it is drained.
  std::lock_guard<std::mutex> lock(mu_);
  draining_ = true;
  for (IngestReactor* stream : open_) stream->Drain();
}

}  // namespace mapd::service
