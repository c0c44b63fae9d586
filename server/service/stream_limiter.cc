#include "service/stream_limiter.h"

#include <algorithm>

namespace mapd::service {
namespace {

// Buckets kept at most; beyond it full buckets are dropped (a full bucket is
// what a new one starts as, so dropping it changes nothing).
constexpr size_t kMaxBuckets = 65536;

}  // namespace

StreamSlot& StreamSlot::operator=(StreamSlot&& other) noexcept {
  if (this != &other) {
    Release();
    owner_ = other.owner_;
    other.owner_ = nullptr;
  }
  return *this;
}

void StreamSlot::Release() {
  if (owner_ != nullptr) owner_->open_.fetch_sub(1);
  owner_ = nullptr;
}

StreamLimiter::StreamLimiter(const StreamLimits& limits) : limits_(limits) {}

std::string StreamLimiter::PeerHost(const std::string& peer) {
  if (peer.rfind("ipv4:", 0) != 0 && peer.rfind("ipv6:", 0) != 0) return peer;
  const size_t colon = peer.rfind(':');
  return colon == std::string::npos || colon < 5 ? peer : peer.substr(0, colon);
}

bool StreamLimiter::TakeToken(const std::string& host) {
  const auto now = std::chrono::steady_clock::now();
  std::lock_guard<std::mutex> lock(mu_);
  auto it = buckets_.find(host);
  if (it == buckets_.end()) {
    if (buckets_.size() >= kMaxBuckets) {
      for (auto b = buckets_.begin(); b != buckets_.end();) {
        const double refill = std::chrono::duration<double>(now - b->second.last).count() *
                              limits_.stream_opens_per_s;
        b = b->second.tokens + refill >= limits_.stream_open_burst ? buckets_.erase(b)
                                                                   : std::next(b);
      }
      if (buckets_.size() >= kMaxBuckets) return false;  // that many distinct clients, all busy
    }
    it = buckets_.emplace(host, Bucket{limits_.stream_open_burst, now}).first;
  }
  Bucket& b = it->second;
  b.tokens = std::min(
      limits_.stream_open_burst,
      b.tokens + std::chrono::duration<double>(now - b.last).count() * limits_.stream_opens_per_s);
  b.last = now;
  if (b.tokens < 1.0) return false;
  b.tokens -= 1.0;
  return true;
}

Status StreamLimiter::TryOpen(const std::string& peer, StreamSlot* slot) {
  if (open_.fetch_add(1) >= limits_.max_streams) {
    open_.fetch_sub(1);
    refused_.fetch_add(1);
    return Status::ResourceExhausted(
        "mapd has limits.max_streams = " + std::to_string(limits_.max_streams) +
        " streams open; retry later");
  }
  if (!TakeToken(PeerHost(peer))) {
    open_.fetch_sub(1);
    refused_.fetch_add(1);
    return Status::ResourceExhausted(
        "this client opens streams faster than limits.stream_opens_per_s = " +
        std::to_string(limits_.stream_opens_per_s) + " per second; retry later");
  }
  admitted_.fetch_add(1);
  *slot = StreamSlot(this);
  return Status::Ok();
}

}  // namespace mapd::service
