#include "service/write_health.h"

#include <algorithm>

namespace mapd::service {

void WriteHealth::SetListener(std::function<void(const Status&)> listener) {
  std::lock_guard<std::mutex> lock(mu_);
  listener_ = std::move(listener);
}

bool WriteHealth::IsStorageFailure(const Status& s) {
  switch (s.code()) {
    case StatusCode::kResourceExhausted:  // SQLITE_FULL
    case StatusCode::kInternal:           // I/O errors, read-only, corruption
    case StatusCode::kUnavailable:        // SQLITE_BUSY past busy_timeout_ms
      return true;
    default:
      return false;
  }
}

void WriteHealth::Record(const Status& outcome, Attempt attempt) {
  std::function<void(const Status&)> notify;
  Status now;
  {
    std::lock_guard<std::mutex> lock(mu_);
    const bool was_ok = failure_.ok();
    if (IsStorageFailure(outcome)) {
      failure_ = outcome;
      consecutive_ += 1;
      if (!was_ok) return;  // still failing: one change, one notification
      now = outcome;
    } else if (outcome.ok()) {
      if (!was_ok && failure_.code() == StatusCode::kResourceExhausted &&
          attempt != Attempt::kProbe) {
        return;  // still full until the probe finds room
      }
      consecutive_ = 0;
      if (was_ok) return;
      failure_ = Status::Ok();
    } else {
      return;
    }
    notify = listener_;
  }
  if (notify) notify(now);
}

bool WriteHealth::ok() const {
  std::lock_guard<std::mutex> lock(mu_);
  return failure_.ok();
}

Status WriteHealth::status() const {
  std::lock_guard<std::mutex> lock(mu_);
  if (failure_.ok()) return failure_;
  return Status::Unavailable("the database does not take writes (" + failure_.message() +
                             "); nothing was stored, retry later");
}

std::chrono::milliseconds WriteHealth::Backoff() const {
  std::lock_guard<std::mutex> lock(mu_);
  const int doublings = std::clamp(consecutive_ - 1, 0, 5);
  return std::min(std::chrono::milliseconds(50 << doublings), std::chrono::milliseconds(1000));
}

}  // namespace mapd::service
