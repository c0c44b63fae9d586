// Is an address loopback, and does a web request's Host name one? The
// plaintext-listen rule (config.cc) and the web view's DNS-rebinding defence
// (web_server.cc) decide by what an address IS, not how it is spelled: 127.1,
// 127.0.0.2, ::ffff:127.0.0.1 and localhost are all loopback (issue 43:
// `--http.address 127.1` turned the web view's check off).
#ifndef MAPD_SERVICE_LOOPBACK_H_
#define MAPD_SERVICE_LOOPBACK_H_

#include <string>
#include <string_view>

namespace mapd::service {

// True when every address `address` resolves to (as the web server binds
// it: numerically, or through the resolver for a name) is a loopback address
// (127.0.0.0/8, ::1, or IPv4-mapped 127.0.0.0/8). False for a wildcard
// (0.0.0.0, ::) or an address that does not resolve.
bool IsLoopbackAddress(const std::string& address);

// True when a Host header names a loopback address literally ("127.0.0.1",
// "127.1:8080", "[::1]:8080") or is "localhost" (with any port). Any other
// name is refused: after DNS rebinding, a foreign name resolves to 127.0.0.1
// too, so names other than localhost are never looked up.
bool IsLoopbackHost(std::string_view host);

}  // namespace mapd::service

#endif  // MAPD_SERVICE_LOOPBACK_H_
