// Reading a real mapd's Prometheus metrics from its web port, for tests and
// benchmarks that count what reached it. Header-only, POSIX.
#ifndef MAPD_TESTS_COMMON_MAPD_METRICS_H_
#define MAPD_TESTS_COMMON_MAPD_METRICS_H_

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <sstream>
#include <string>

namespace mapd::testing {

// The body of GET /metrics on 127.0.0.1:`web_port` (a plain HTTP/1.0
// request); empty if it cannot be read.
inline std::string ReadMetrics(int web_port) {
  const int fd = socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
  if (fd < 0) return "";
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  addr.sin_port = htons(static_cast<uint16_t>(web_port));
  std::string body;
  const std::string request = "GET /metrics HTTP/1.0\r\nHost: 127.0.0.1\r\n\r\n";
  if (connect(fd, reinterpret_cast<sockaddr*>(&addr), sizeof addr) == 0 &&
      write(fd, request.data(), request.size()) == static_cast<ssize_t>(request.size())) {
    char buf[65536];
    for (ssize_t n; (n = read(fd, buf, sizeof buf)) > 0;) body.append(buf, static_cast<size_t>(n));
  }
  close(fd);
  return body;
}

// The sum of grpc_server_handled_total for Ingest (every status: a stream
// reset by its client counts too); -1 if the metrics cannot be read.
inline double IngestCallsHandled(int web_port) {
  const std::string body = ReadMetrics(web_port);
  if (body.empty()) return -1;
  double total = 0;
  std::istringstream lines(body);
  for (std::string line; std::getline(lines, line);) {
    if (line.rfind("grpc_server_handled_total{", 0) == 0 &&
        line.find("grpc_method=\"Ingest\"") != std::string::npos)
      total += std::stod(line.substr(line.rfind(' ') + 1));
  }
  return total;
}

}  // namespace mapd::testing

#endif  // MAPD_TESTS_COMMON_MAPD_METRICS_H_
