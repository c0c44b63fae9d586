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
#include <mutex>
#include <string>
#include <unordered_map>

#include "common/status.h"

namespace mapd::service {

// Limits on connections and streams (floods, slow or idle clients).
struct StreamLimits {
  // Long-lived streams (Ingest, UploadSubmap) open at once, server-wide;
  // beyond it a new one is answered RESOURCE_EXHAUSTED at once.
  size_t max_streams = 2000;
  uint32_t max_streams_per_connection = 100;  // HTTP/2 SETTINGS_MAX_CONCURRENT_STREAMS
  // Token bucket per client address (host, port ignored): stream opens per
  // second, and the burst allowed above that rate.
  double stream_opens_per_s = 200.0;
  double stream_open_burst = 400.0;
  double keepalive_time_s = 60.0;       // ping an idle connection this often
  double keepalive_timeout_s = 20.0;    // ... and drop it when the ping is not answered within this
  double min_client_ping_interval_s = 10.0;  // clients pinging more often are dropped (ping flood)
  double max_connection_idle_s = 600.0; // close connections without streams after this; 0 = never
  double max_connection_age_s = 0.0;    // close any connection after this (gracefully); 0 = never
  // A read (GetFeatureMap) waits at most this long for the fuser to reflect
  // every acknowledged batch, unless the request asks for longer; then it
  // answers with the map as it is (map_version and fusion_pending say how old).
  double read_wait_s = 0.2;
  double max_read_wait_s = 30.0;        // the longest wait a request may ask for
  uint32_t log_lines_per_s = 20;        // per event; the rest is counted in one `log_suppressed` line
};

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
