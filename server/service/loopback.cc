#include "service/loopback.h"

#include <arpa/inet.h>
#include <netdb.h>
#include <netinet/in.h>
#include <sys/socket.h>

#include <cstring>

namespace mapd::service {
namespace {

bool IsLoopbackV4(const in_addr& a) { return (ntohl(a.s_addr) >> 24) == 127; }

bool IsLoopbackV6(const in6_addr& a) {
  if (IN6_IS_ADDR_LOOPBACK(&a)) return true;
  if (!IN6_IS_ADDR_V4MAPPED(&a)) return false;
  in_addr v4;
  std::memcpy(&v4, &a.s6_addr[12], sizeof v4);
  return IsLoopbackV4(v4);
}

}  // namespace

bool IsLoopbackAddress(const std::string& address) {
  addrinfo hints{};
  hints.ai_family = AF_UNSPEC;
  hints.ai_socktype = SOCK_STREAM;
  addrinfo* found = nullptr;
  if (getaddrinfo(address.c_str(), nullptr, &hints, &found) != 0 || found == nullptr) return false;
  bool all = true;
  for (const addrinfo* a = found; a != nullptr; a = a->ai_next) {
    if (a->ai_family == AF_INET) {
      all = all && IsLoopbackV4(reinterpret_cast<const sockaddr_in*>(a->ai_addr)->sin_addr);
    } else if (a->ai_family == AF_INET6) {
      all = all && IsLoopbackV6(reinterpret_cast<const sockaddr_in6*>(a->ai_addr)->sin6_addr);
    } else {
      all = false;
    }
  }
  freeaddrinfo(found);
  return all;
}

bool IsLoopbackHost(std::string_view host) {
  std::string name;
  if (!host.empty() && host.front() == '[') {  // [v6]:port
    const size_t close = host.find(']');
    if (close == std::string_view::npos) return false;
    const std::string_view rest = host.substr(close + 1);
    if (!rest.empty() && rest.front() != ':') return false;
    name = std::string(host.substr(1, close - 1));
    in6_addr a6;
    return inet_pton(AF_INET6, name.c_str(), &a6) == 1 && IsLoopbackV6(a6);
  }
  const size_t colon = host.find(':');
  name = std::string(host.substr(0, colon));
  if (name == "localhost") return true;
  // inet_aton takes the short forms a bound address may have (127.1), and
  // only digits and dots: no name reaches the resolver.
  in_addr a4;
  return inet_aton(name.c_str(), &a4) != 0 && IsLoopbackV4(a4);
}

}  // namespace mapd::service
