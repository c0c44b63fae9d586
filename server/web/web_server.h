// WebServer: the web view on an HTTP port of its own (http.port; off by
// default, loopback by default). Read-only except merge decisions:
//
//   GET  /                          the page (embedded at build time: page/index.html)
//   GET  /api/features              the published map (lines and planes) as JSON
//   GET  /api/events                server-sent events of the change feed (WatchHub):
//                                   `resync` (the whole map) and `change` events,
//                                   id = map_version; Last-Event-ID resumes
//   GET  /api/robots                robots, their last pose and a short trail
//   GET  /api/merges[?state=S]      merge records
//   POST /api/merges/ID/approve     a proposed merge takes effect
//   POST /api/merges/ID/reject      ... ends without effect (JSON body {"reason": "..."})
//   GET  /api/global-map.png        top view of the merged global map (404 before one)
//   GET  /metrics                   Prometheus text
//   GET  /api/maps                  the maps the caller may see (the page's picker)
//
// Every route but / and /api/maps is about one map: `?map=ID` (absent: the
// default map); a map the server does not serve is 404, one the caller's
// token is not scoped to 403.
//
// Who: the gRPC side's rules (service/access_control.h) over an
// `Authorization: Bearer <token>` header: GETs need read_map and decisions
// merge (operator, admin) once tokens are in use; in the open mode (loopback,
// no token ever made, auth.required false) everything is allowed. Errors are
// JSON {"error": "..."} with a 4xx/5xx status naming the problem.
//
// It sees only the Core interface. Thread safety: Start and Stop from one
// thread; requests run on the server's own pool.
#ifndef MAPD_WEB_WEB_SERVER_H_
#define MAPD_WEB_WEB_SERVER_H_

#include <atomic>
#include <functional>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "common/status.h"
#include "service/access_control.h"
#include "service/core.h"

namespace httplib {
class Server;
}

namespace mapd::web {

struct WebServerOptions {
  std::string address = "127.0.0.1";
  int port = 0;  // 0: any free port (tests); mapd starts no web server for http.port 0
  service::AuthOptions auth;
  // The server's maps (service/map_directory.h): their ids, and a map's core
  // (null when not served). Unset: the one core Start() is given, as "default".
  std::function<std::vector<std::string>()> list_maps;
  // The map's core, held while a request uses it (MapDirectory::FindCore).
  std::function<std::shared_ptr<service::Core>(const std::string&)> find_map;
};

class WebServer {
 public:
  // Binds and starts serving; Unavailable naming the address and port when
  // it cannot listen (in use, not permitted, no such address).
  static StatusOr<std::unique_ptr<WebServer>> Start(service::Core* core,
                                                    const WebServerOptions& options);
  ~WebServer();  // Stop()
  int port() const { return port_; }
  // Ends event streams (within ~0.5 s), stops listening, waits for requests.
  void Stop();

 private:
  WebServer(service::Core* core, const WebServerOptions& options);
  void Route();

  service::Core* const core_;  // the default map's
  const WebServerOptions options_;
  const bool loopback_;  // bound to a loopback address: only loopback Host headers
  service::AccessControl access_;
  std::unique_ptr<httplib::Server> http_;
  std::thread thread_;
  int port_ = 0;
  std::atomic<bool> stopping_{false};
  std::atomic<int> event_streams_{0};
};

}  // namespace mapd::web

#endif  // MAPD_WEB_WEB_SERVER_H_
