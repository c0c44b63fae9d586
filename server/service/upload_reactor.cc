#include "service/upload_reactor.h"

#include <utility>

#include "service/status_mapping.h"
#include "service/submap_service.h"

namespace mapd::service {

namespace pb = mapserver::v1;

UploadReactor::UploadReactor(SubmapService* service, grpc::CallbackServerContext* context,
                             pb::SubmapInfo* response, StreamSlot slot, Principal caller,
                             CallHold hold)
    : hold_(std::move(hold)),
      service_(service),
      context_(context),
      response_(response),
      slot_(std::move(slot)),
      caller_(std::move(caller)) {
  std::lock_guard<std::mutex> lock(mu_);
  last_activity_ = std::chrono::steady_clock::now();
  StartRead(&message_);
}

void UploadReactor::OnReadDone(bool ok) {
  std::unique_lock<std::mutex> lock(mu_);
  if (finished_) return;  // expired, cancelled or refused meanwhile
  last_activity_ = std::chrono::steady_clock::now();
  if (!ok) {
    // The client half-closed, or went away (a partial file is never stored).
    if (context_->IsCancelled()) {
      lock.unlock();
      FinishOnce(grpc::Status(grpc::StatusCode::CANCELLED,
                              "the upload was cancelled; nothing was stored"));
      return;
    }
    if (messages_ == 0) {
      lock.unlock();
      FinishOnce(grpc::Status(grpc::StatusCode::INVALID_ARGUMENT,
                              "empty upload: the first message must be a SubmapHeader"));
      return;
    }
    storing_ = true;
    lock.unlock();
    service_->RunStore([this] {
      grpc::Status s = service_->StoreUpload(header_, std::move(bytes_), response_, caller_);
      FinishOnce(s);
    });
    return;
  }
  const size_t index = messages_++;
  lock.unlock();
  grpc::Status s = index == 0 ? service_->CheckUploadHeader(message_, &header_)
                              : service_->AppendUploadChunk(header_, index - 1, &message_, &bytes_);
  if (!s.ok()) {
    FinishOnce(s);
    return;
  }
  if (index == 0 && !CallerMayUpload()) return;
  lock.lock();
  if (!finished_) StartRead(&message_);
}

bool UploadReactor::CallerMayUpload() {
  if (Authorize(caller_, Permission::kWrite, "UploadSubmap", header_.robot_id()).ok()) return true;
  {
    std::lock_guard<std::mutex> lock(mu_);
    if (finished_) return false;  // cancelled or expired meanwhile: nothing to answer
    storing_ = true;              // the audit's completion ends the call
  }
  service_->access()->CheckAsync(
      caller_, Permission::kWrite, "UploadSubmap", header_.robot_id(),
      SubmapService::UploadTarget(header_), [this](const Status& may) {
        // Authorize is a pure function: CheckAsync refuses too.
        FinishOnce(may.ok() ? grpc::Status(grpc::StatusCode::INTERNAL,
                                           "authorization changed during the upload")
                            : ToGrpcStatus(may));
      });
  return false;
}

void UploadReactor::ExpireIfIdle(std::chrono::steady_clock::time_point now, double idle_s) {
  {
    std::lock_guard<std::mutex> lock(mu_);
    if (finished_ || storing_ ||
        std::chrono::duration<double>(now - last_activity_).count() < idle_s)
      return;
  }
  FinishOnce(grpc::Status(grpc::StatusCode::DEADLINE_EXCEEDED,
                          "the upload sent nothing for limits.upload_idle_timeout_s = " +
                              std::to_string(idle_s) + " s; nothing was stored"));
}

void UploadReactor::OnCancel() {
  {
    std::lock_guard<std::mutex> lock(mu_);
    if (storing_) return;  // every byte was in: the store finishes the call
  }
  FinishOnce(
      grpc::Status(grpc::StatusCode::CANCELLED, "the upload was cancelled; nothing was stored"));
}

void UploadReactor::FinishOnce(const grpc::Status& status) {
  {
    std::lock_guard<std::mutex> lock(mu_);
    if (finished_) return;
    finished_ = true;
  }
  // The places are given back before the client sees the status, so that a
  // client's next upload is not refused by this one's tail.
  slot_.Release();
  service_->ReleaseUploadSlot();
  Finish(status);
}

void UploadReactor::OnDone() {
  service_->EndUpload(this);
  delete this;
}

}  // namespace mapd::service
