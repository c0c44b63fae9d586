#include "client/robot/robot_client.h"

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <optional>

namespace mapd::robot {

namespace pb = mapserver::v1;

// While failing over, the pause between tries stays under this many initial
// backoffs (ReaderLoop).
constexpr int kFailoverBackoffFactor = 4;

RobotClient::RobotClient(std::shared_ptr<grpc::Channel> channel, RobotClientOptions options)
    : channel_(std::move(channel)),
      stub_(pb::MapService::NewStub(channel_)),
      first_channel_(channel_),
      options_(std::move(options)) {
  reader_ = std::thread([this] { ReaderLoop(); });
}

RobotClient::~RobotClient() {
  {
    std::lock_guard<std::mutex> lock(mu_);
    CancelLocked();
  }
  if (reader_.joinable()) reader_.join();
}

void RobotClient::Send(pb::ObservationBatch batch) {
  {
    // Back-pressure: wait for room in the window of unacknowledged batches.
    std::unique_lock<std::mutex> lock(mu_);
    cv_.wait(lock, [this] {
      return pending_.size() < options_.max_unacknowledged || gave_up_ || stopping_ || reader_done_;
    });
  }
  // write_mu_ is held from queueing to writing so that a reconnect (which
  // resends everything queued) cannot interleave and send this batch twice.
  std::lock_guard<std::mutex> write_lock(write_mu_);
  {
    std::lock_guard<std::mutex> lock(mu_);
    const Key key(batch.session_id(), batch.seq());
    auto it = order_of_.find(key);
    if (it != order_of_.end()) pending_.erase(it->second);  // sent again before its ack
    const uint64_t order = next_order_++;
    order_of_[key] = order;
    pending_.emplace(order, batch);  // a copy: an ack may erase it while we write
    ++counts_.sent;
    if (gave_up_ || stopping_) return;
  }
  // Without a stream (between reconnects) the reader sends it on reconnecting.
  // A failed Write means a broken stream: the reader sees it and reconnects.
  if (stream_ != nullptr && !half_closed_) stream_->Write(batch);
}

bool RobotClient::WaitForAcks(std::chrono::milliseconds timeout) {
  std::unique_lock<std::mutex> lock(mu_);
  cv_.wait_for(lock, timeout, [this] { return pending_.empty() || gave_up_ || reader_done_; });
  return pending_.empty();
}

grpc::Status RobotClient::Finish(std::chrono::milliseconds timeout) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  const bool all_acked = WaitForAcks(timeout);
  if (all_acked) {
    {
      std::lock_guard<std::mutex> lock(mu_);
      closing_ = true;
    }
    // Half-close: the server ends the stream once its last ack is written.
    std::lock_guard<std::mutex> write_lock(write_mu_);
    if (stream_ != nullptr && !half_closed_) {
      stream_->WritesDone();
      half_closed_ = true;
    }
  }
  {
    std::unique_lock<std::mutex> lock(mu_);
    cv_.wait_until(lock, deadline + std::chrono::seconds(1), [this] { return reader_done_; });
    if (!reader_done_) CancelLocked();
  }
  if (reader_.joinable()) reader_.join();

  std::lock_guard<std::mutex> lock(mu_);
  if (pending_.empty()) return grpc::Status::OK;
  if (gave_up_) return last_error_;
  char message[128];
  std::snprintf(message, sizeof(message), "%zu batches still unacknowledged after %.1f s",
                pending_.size(), std::chrono::duration<double>(timeout).count());
  return grpc::Status(grpc::StatusCode::DEADLINE_EXCEEDED, message);
}

IngestCounts RobotClient::counts() const {
  std::lock_guard<std::mutex> lock(mu_);
  return counts_;
}

std::vector<Rejection> RobotClient::rejections() const {
  std::lock_guard<std::mutex> lock(mu_);
  return rejections_;
}

size_t RobotClient::unacknowledged() const {
  std::lock_guard<std::mutex> lock(mu_);
  return pending_.size();
}

void RobotClient::CancelLocked() {
  stopping_ = true;
  if (cancel_target_ != nullptr) cancel_target_->TryCancel();
  cv_.notify_all();
}

void RobotClient::OpenStreamLocked() {
  context_ = std::make_unique<grpc::ClientContext>();
  if (!options_.token.empty()) context_->AddMetadata("authorization", "Bearer " + options_.token);
  if (!options_.map_id.empty()) context_->AddMetadata("mapd-map-id", options_.map_id);
  // It goes to the owner itself: redirected there, not relayed (mapd's map_forwarder.h).
  if (options_.connect) context_->AddMetadata("mapd-follows-redirects", "1");
  stream_ = stub_->Ingest(context_.get());
  half_closed_ = false;
  std::vector<pb::ObservationBatch> resend;
  bool closing = false;
  {
    std::lock_guard<std::mutex> lock(mu_);
    cancel_target_ = context_.get();
    if (stopping_) context_->TryCancel();
    resend.reserve(pending_.size());
    for (const auto& [order, batch] : pending_) resend.push_back(batch);
    closing = closing_;
  }
  for (const pb::ObservationBatch& batch : resend) {
    if (!stream_->Write(batch)) break;  // broken again; the reader will see it
  }
  if (closing) {
    stream_->WritesDone();
    half_closed_ = true;
  }
}

void RobotClient::ReaderLoop() {
  using Clock = std::chrono::steady_clock;
  std::optional<Clock::time_point> failing_since;  // start of the current run of failures
  auto backoff = options_.initial_backoff;
  bool first_stream = true;
  // Every server serves "default"; another map is asked about once.
  bool map_checked = options_.map_id.empty() || options_.map_id == "default";
  for (;;) {
    {
      std::lock_guard<std::mutex> lock(mu_);
      if (stopping_ || (closing_ && pending_.empty())) break;
      if (!first_stream) ++counts_.reconnects;
    }
    first_stream = false;
    bool got_ack = false;
    grpc::Status status;
    std::string redirect;  // the map's owner, when this mapd does not serve it
    // Set when the map is being taken over: how soon the server expects to know more.
    std::optional<std::chrono::milliseconds> retry_after;
    if (!map_checked) {
      status = CheckMap();
      map_checked = status.ok();
    }
    if (map_checked) {
      Stream* stream = nullptr;
      {
        std::lock_guard<std::mutex> write_lock(write_mu_);
        OpenStreamLocked();
        stream = stream_.get();
      }
      pb::IngestAck ack;
      while (stream->Read(&ack)) {
        if (HandleAck(ack)) got_ack = true;
      }
      {
        std::lock_guard<std::mutex> lock(mu_);
        cancel_target_ = nullptr;
      }
      {
        std::lock_guard<std::mutex> write_lock(write_mu_);
        status = stream_->Finish();
        const auto& trailing = context_->GetServerTrailingMetadata();
        if (auto it = trailing.find("mapd-map-owner"); it != trailing.end()) {
          redirect.assign(it->second.data(), it->second.size());
        }
        if (auto it = trailing.find("mapd-retry-after-ms"); it != trailing.end()) {
          retry_after = std::chrono::milliseconds(
              std::atoi(std::string(it->second.data(), it->second.size()).c_str()));
        }
        stream_.reset();
        context_.reset();
      }
    }

    std::unique_lock<std::mutex> lock(mu_);
    if (stopping_ || (closing_ && pending_.empty())) break;
    const Clock::time_point now = Clock::now();
    if (got_ack || !failing_since) {
      failing_since = now;
      if (got_ack) backoff = options_.initial_backoff;
    }
    last_error_ =
        status.ok() ? grpc::Status(grpc::StatusCode::UNAVAILABLE,
                                   "the server ended the Ingest stream with " +
                                       std::to_string(pending_.size()) + " batches unacknowledged")
                    : status;
    const Clock::time_point give_up_at = *failing_since + options_.give_up_after;
    // Final: retrying cannot help (credentials, or a map the server lacks).
    const bool refused = status.error_code() == grpc::StatusCode::UNAUTHENTICATED ||
                         status.error_code() == grpc::StatusCode::PERMISSION_DENIED ||
                         status.error_code() == grpc::StatusCode::FAILED_PRECONDITION ||
                         status.error_code() == grpc::StatusCode::NOT_FOUND;
    if (now >= give_up_at || refused) {
      gave_up_ = true;
      break;
    }
    // A redirect is followed after the shortest pause: the owner is known. A
    // takeover in progress is asked about again as often as it may end.
    if (!redirect.empty() && options_.connect) backoff = options_.initial_backoff;
    const auto pause = retry_after ? std::max(options_.initial_backoff, *retry_after) : backoff;
    cv_.wait_for(lock, pause, [this] { return stopping_; });
    if (!retry_after) backoff = std::min(backoff * 2, options_.max_backoff);
    lock.unlock();
    if (MoveAfterFailure(status, redirect, give_up_at)) {
      // Failing over: the map's new owner takes it within a few seconds, and
      // the robot should find it within a fraction of one, not after a
      // backoff grown on the instances that were not it yet.
      backoff = std::min(backoff, kFailoverBackoffFactor * options_.initial_backoff);
      std::lock_guard<std::mutex> counted(mu_);
      ++counts_.redirects;
    }
  }
  std::lock_guard<std::mutex> lock(mu_);
  reader_done_ = true;
  cv_.notify_all();
}

bool RobotClient::MoveAfterFailure(const grpc::Status& status, const std::string& redirect,
                                   std::chrono::steady_clock::time_point give_up_at) {
  if (!options_.connect) {
    WaitForChannel(give_up_at);
    return false;
  }
  if (!redirect.empty()) {
    ConnectTo(redirect);
    return true;
  }
  if (options_.addresses.empty() || status.error_code() != grpc::StatusCode::UNAVAILABLE) {
    WaitForChannel(give_up_at);
    return false;
  }
  // Unreachable, or its map is being taken over: give the current server a
  // little while (a restart, or the takeover finishing), then try the next.
  // A refused connection (the process is gone) moves on at once.
  const auto deadline =
      std::min(give_up_at, std::chrono::steady_clock::now() + options_.max_backoff);
  for (grpc_connectivity_state state = channel_->GetState(true);
       state != GRPC_CHANNEL_READY && state != GRPC_CHANNEL_TRANSIENT_FAILURE;
       state = channel_->GetState(true)) {
    if (!channel_->WaitForStateChange(state, std::chrono::system_clock::now() +
                                                 (deadline - std::chrono::steady_clock::now()))) {
      break;  // the deadline passed
    }
  }
  if (channel_->GetState(false) == GRPC_CHANNEL_READY) return false;
  const size_t n = options_.addresses.size();
  const size_t i = next_address_++ % (n + 1);
  std::lock_guard<std::mutex> write_lock(write_mu_);
  channel_ = i < n ? options_.connect(options_.addresses[i]) : first_channel_;
  stub_ = pb::MapService::NewStub(channel_);
  return true;
}

void RobotClient::ConnectTo(const std::string& address) {
  std::shared_ptr<grpc::Channel> channel = options_.connect(address);
  std::lock_guard<std::mutex> write_lock(write_mu_);
  channel_ = std::move(channel);
  stub_ = pb::MapService::NewStub(channel_);
}

grpc::ChannelArguments RobotChannelArguments() {
  grpc::ChannelArguments args;
  args.SetInt(GRPC_ARG_INITIAL_RECONNECT_BACKOFF_MS, 200);
  args.SetInt(GRPC_ARG_MIN_RECONNECT_BACKOFF_MS, 200);
  args.SetInt(GRPC_ARG_MAX_RECONNECT_BACKOFF_MS, 2000);
  args.SetInt(GRPC_ARG_KEEPALIVE_TIME_MS, 5000);
  args.SetInt(GRPC_ARG_KEEPALIVE_TIMEOUT_MS, 3000);
  args.SetInt(GRPC_ARG_KEEPALIVE_PERMIT_WITHOUT_CALLS, 0);  // only while a stream is open
  args.SetInt(GRPC_ARG_HTTP2_MAX_PINGS_WITHOUT_DATA, 0);    // a quiet stream keeps pinging
  return args;
}

grpc::Status CheckMapServed(pb::MapService::Stub* stub, grpc::ClientContext* context,
                            const std::string& map) {
  pb::ListMapsResponse maps;
  const grpc::Status s = stub->ListMaps(context, pb::ListMapsRequest(), &maps);
  if (s.error_code() == grpc::StatusCode::UNIMPLEMENTED) {
    return grpc::Status(grpc::StatusCode::FAILED_PRECONDITION,
                        "map '" + map +
                            "': the server serves one map and knows no others (a mapd from "
                            "before maps: ListMaps is unimplemented); nothing was sent to it: "
                            "upgrade it, or name no map to use its only one");
  }
  if (!s.ok()) return s;
  std::string names;
  for (const pb::MapInfo& m : maps.maps()) {
    if (m.map_id() == map) return grpc::Status::OK;
    names += (names.empty() ? "" : ", ") + m.map_id();
  }
  return grpc::Status(grpc::StatusCode::NOT_FOUND,
                      "the server does not serve map '" + map + "'; it serves: " + names +
                          " (an admin makes one with mapctl maps create)");
}

grpc::Status RobotClient::CheckMap() {
  grpc::ClientContext call;
  {
    std::lock_guard<std::mutex> lock(mu_);
    if (stopping_) return grpc::Status(grpc::StatusCode::CANCELLED, "stopping");
    cancel_target_ = &call;
  }
  call.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(10));
  if (!options_.token.empty()) call.AddMetadata("authorization", "Bearer " + options_.token);
  const grpc::Status s = CheckMapServed(stub_.get(), &call, options_.map_id);
  std::lock_guard<std::mutex> lock(mu_);
  cancel_target_ = nullptr;
  return s;
}

void RobotClient::WaitForChannel(std::chrono::steady_clock::time_point deadline) {
  // In slices, so that Stop is noticed; GetState(true) starts a connection attempt.
  constexpr auto kSlice = std::chrono::milliseconds(200);
  for (;;) {
    const grpc_connectivity_state state = channel_->GetState(true);
    if (state == GRPC_CHANNEL_READY) return;
    const auto now = std::chrono::steady_clock::now();
    if (now >= deadline) return;
    {
      std::lock_guard<std::mutex> lock(mu_);
      if (stopping_) return;
    }
    const auto until = std::min(
        deadline, now + std::chrono::duration_cast<std::chrono::steady_clock::duration>(kSlice));
    channel_->WaitForStateChange(state, std::chrono::system_clock::now() + (until - now));
  }
}

bool RobotClient::HandleAck(const pb::IngestAck& ack) {
  std::lock_guard<std::mutex> lock(mu_);
  auto it = order_of_.find(Key(ack.session_id(), ack.seq()));
  if (it == order_of_.end()) return false;  // not pending (e.g. a resend's second answer)
  switch (ack.result()) {
    case pb::IngestAck::STORED:
      ++counts_.stored;
      break;
    case pb::IngestAck::DUPLICATE:
      ++counts_.duplicate;
      break;
    case pb::IngestAck::REJECTED:
      // UNAVAILABLE is the server draining, or its database refusing writes
      // for now: not a verdict on the batch. Keep it, and end this stream:
      // the next one (after the backoff, which this does not reset) resends
      // every batch still pending, once the server takes writes again.
      if (ack.code() == grpc::StatusCode::UNAVAILABLE) {
        if (cancel_target_ != nullptr) cancel_target_->TryCancel();
        return false;
      }
      ++counts_.rejected;
      rejections_.push_back(
          {ack.session_id(), ack.seq(), static_cast<grpc::StatusCode>(ack.code()), ack.message()});
      break;
    default:
      return false;  // RESULT_UNSPECIFIED: not final
  }
  pending_.erase(it->second);
  order_of_.erase(it);
  cv_.notify_all();
  return true;
}

}  // namespace mapd::robot
