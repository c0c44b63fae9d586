// Admission of long-lived streams (Ingest, UploadSubmap): a server-wide cap on
// open streams and a token bucket per client address, checked before any
// per-stream state is made, so that a flood of stream opens (or the HTTP/2
// rapid-reset pattern, CVE-2023-44487, which gRPC 1.51 does not blunt by
// itself) costs one refusal each instead of a reactor, a log line and memory.
//
// Thread safety: all methods may be called concurrently.
#ifndef MAPD_SERVICE_STREAM_LIMITER_H_
#define MAPD_SERVICE_STREAM_LIMITER_H_

#include <atomic>
#include <chrono>
#include <cstdint>
#include <memory>
#include <mutex>
#include <string>
#include <unordered_map>

#include "common/status.h"
#include "service/options.h"

namespace mapd::service {

// What keeps a stream's map allocated while the stream is open (a
// MapHold, map_directory.h): a stream outlives the call that opened it.
using CallHold = std::shared_ptr<const void>;

class StreamLimiter;

// One admitted stream; releases its place when destroyed.
class StreamSlot {
 public:
  StreamSlot() = default;
  explicit StreamSlot(StreamLimiter* owner) : owner_(owner) {}
  StreamSlot(StreamSlot&& other) noexcept : owner_(other.owner_) { other.owner_ = nullptr; }
  StreamSlot& operator=(StreamSlot&& other) noexcept;
  StreamSlot(const StreamSlot&) = delete;
  StreamSlot& operator=(const StreamSlot&) = delete;
  ~StreamSlot() { Release(); }
  void Release();

 private:
  StreamLimiter* owner_ = nullptr;
};

class StreamLimiter {
 public:
  explicit StreamLimiter(const StreamLimits& limits);

  // Admits a new stream from `peer` (grpc::ServerContext::peer(), e.g.
  // "ipv4:10.0.0.7:53122"; the port is ignored) or says why not
  // (ResourceExhausted, naming the limit). The slot must outlive the stream.
  Status TryOpen(const std::string& peer, StreamSlot* slot);

  size_t open() const { return open_.load(); }
  uint64_t admitted() const { return admitted_.load(); }  // since the start
  uint64_t refused() const { return refused_.load(); }

  // "ipv4:10.0.0.7:53122" -> "ipv4:10.0.0.7", "ipv6:[::1]:5" -> "ipv6:[::1]".
  static std::string PeerHost(const std::string& peer);

 private:
  friend class StreamSlot;
  struct Bucket {
    double tokens = 0;
    std::chrono::steady_clock::time_point last;
  };
  bool TakeToken(const std::string& host);

  const StreamLimits limits_;
  std::atomic<size_t> open_{0};
  std::atomic<uint64_t> admitted_{0}, refused_{0};
  std::mutex mu_;
  std::unordered_map<std::string, Bucket> buckets_;  // GUARDED_BY(mu_)
};

}  // namespace mapd::service

#endif  // MAPD_SERVICE_STREAM_LIMITER_H_
