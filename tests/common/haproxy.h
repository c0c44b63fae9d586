// HAProxy in front of a test's mapd, run from the shipped configuration
// (deploy/haproxy.cfg, whose addresses come from the environment), and CPU
// hogs to load the machine beside it. POSIX only; header-only.
//
//   HaproxyProcess proxy = StartHaproxy(kHaproxyConfig, mapd.address, dir.File("haproxy.log"));
//   if (proxy.pid < 0) GTEST_SKIP() << "haproxy is not installed";
//   ... connect to proxy.address ...
//   Stop(proxy.pid);
#ifndef MAPD_TESTS_COMMON_HAPROXY_H_
#define MAPD_TESTS_COMMON_HAPROXY_H_

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <chrono>
#include <csignal>
#include <string>
#include <thread>
#include <vector>

#include "common/process.h"

namespace mapd::testing {

inline constexpr const char* kHaproxyBinary = "/usr/sbin/haproxy";

// A loopback TCP port nobody listens on now (bound, read, released).
inline int FreeLoopbackPort() {
  const int fd = socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  socklen_t len = sizeof addr;
  int port = 0;
  if (bind(fd, reinterpret_cast<sockaddr*>(&addr), sizeof addr) == 0 &&
      getsockname(fd, reinterpret_cast<sockaddr*>(&addr), &len) == 0)
    port = ntohs(addr.sin_port);
  close(fd);
  return port;
}

inline bool AcceptsConnections(int port) {
  const int fd = socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  addr.sin_port = htons(static_cast<uint16_t>(port));
  const bool ok = connect(fd, reinterpret_cast<sockaddr*>(&addr), sizeof addr) == 0;
  close(fd);
  return ok;
}

struct HaproxyProcess {
  pid_t pid = -1;       // -1: haproxy is missing or did not start
  std::string address;  // "127.0.0.1:PORT", its gRPC frontend
  std::string log_path;
  std::string log() const { return internal::ReadFile(log_path); }
};

// Starts `haproxy -f config` in the foreground with its frontend on a free
// loopback port and `backend` ("HOST:PORT", mapd) behind it; waits for the
// port to accept connections.
inline HaproxyProcess StartHaproxy(const std::string& config, const std::string& backend,
                                   const std::string& log_path) {
  HaproxyProcess p;
  p.log_path = log_path;
  if (access(kHaproxyBinary, X_OK) != 0) return p;
  const int port = FreeLoopbackPort();
  p.address = "127.0.0.1:" + std::to_string(port);
  const int log_fd = open(log_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (log_fd < 0) return p;
  p.pid = internal::Spawn({kHaproxyBinary, "-db", "-f", config}, -1, log_fd, log_fd,
                          {"MAPD_PROXY_BIND=" + p.address, "MAPD_BACKEND=" + backend});
  close(log_fd);
  for (int i = 0; i < 250 && p.pid > 0; ++i) {
    if (AcceptsConnections(port)) return p;
    int status = 0;
    if (waitpid(p.pid, &status, WNOHANG) == p.pid) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  if (p.pid > 0) Stop(p.pid, SIGKILL);
  p.pid = -1;
  return p;
}

// `n` processes that spin until Stop: a busy machine (a build, a benchmark)
// competing with mapd for the cores at the same priority.
class CpuHogs {
 public:
  explicit CpuHogs(int n) {
    for (int i = 0; i < n; ++i) {
      const pid_t pid = fork();
      if (pid == 0) {
        for (volatile uint64_t x = 0;; x = x + 1) {
        }
      }
      if (pid > 0) pids_.push_back(pid);
    }
  }
  ~CpuHogs() {
    for (const pid_t pid : pids_) Stop(pid, SIGKILL);
  }
  CpuHogs(const CpuHogs&) = delete;
  CpuHogs& operator=(const CpuHogs&) = delete;

 private:
  std::vector<pid_t> pids_;
};

}  // namespace mapd::testing

#endif  // MAPD_TESTS_COMMON_HAPROXY_H_
