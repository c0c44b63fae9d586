// Shared by the web view's handlers (not part of its interface).
#ifndef MAPD_WEB_HTTP_UTIL_H_
#define MAPD_WEB_HTTP_UTIL_H_

#include <atomic>
#include <cstdint>
#include <memory>
#include <string>

#include "common/status.h"
#include "service/core.h"
#include "web/http.h"

namespace mapd::web {

// `status` as an HTTP status and a JSON body {"error": "..."}.
void SendError(httplib::Response& res, const Status& status);
// A decimal id: InvalidArgument naming `what` and the text otherwise.
StatusOr<uint64_t> ParseId(const std::string& text, const std::string& what);

// GET /api/events (events.cc). Ends when the client goes, at `stopping`, or
// when the hub closes; holds `core` until then.
void ServeEvents(std::shared_ptr<service::Core> core, const httplib::Request& req,
                 httplib::Response& res, const std::atomic<bool>* stopping,
                 std::atomic<int>* streams);
// GET /api/robots (robots.cc).
void ServeRobots(service::Core* core, httplib::Response& res);
// GET /api/global-map.png (global_map.cc).
void ServeGlobalMap(service::Core* core, httplib::Response& res);

// The page (page/index.html, embedded by CMake into page.cc).
extern const char kIndexHtml[];

}  // namespace mapd::web

#endif  // MAPD_WEB_HTTP_UTIL_H_
