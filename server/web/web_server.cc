#include "web/web_server.h"

#include <cctype>
#include <chrono>

#include "common/text_escape.h"
#include "service/auth.h"
#include "service/log.h"
#include "service/loopback.h"
#include "service/merge_review.h"
#include "web/http.h"
#include "web/http_util.h"
#include "web/metrics.h"
#include "web/web_json.h"

namespace mapd::web {
namespace {

// Event streams hold a pool thread each (at most 16, events.cc): the pool
// keeps threads for the page's other requests beyond them.
constexpr int kThreads = 24;

int HttpStatus(StatusCode code) {
  switch (code) {
    case StatusCode::kOk:
      return 200;
    case StatusCode::kInvalidArgument:
      return 400;
    case StatusCode::kUnauthenticated:
      return 401;
    case StatusCode::kPermissionDenied:
      return 403;
    case StatusCode::kNotFound:
      return 404;
    case StatusCode::kAlreadyExists:
    case StatusCode::kFailedPrecondition:
      return 409;
    case StatusCode::kResourceExhausted:
      return 429;
    case StatusCode::kUnimplemented:
      return 501;
    case StatusCode::kUnavailable:
      return 503;
    default:
      return 500;
  }
}

void SendJson(httplib::Response& res, const Json& body) {
  res.set_content(Dump(body), "application/json");
}

}  // namespace

void SendError(httplib::Response& res, const Status& status) {
  res.status = HttpStatus(status.code());
  if (status.code() == StatusCode::kUnauthenticated)
    res.set_header("WWW-Authenticate", "Bearer realm=\"mapd\"");
  SendJson(res, {{"error", status.message()}, {"code", StatusCodeName(status.code())}});
}

StatusOr<uint64_t> ParseId(const std::string& text, const std::string& what) {
  const bool digits = !text.empty() && text.size() <= 18 &&
                      std::all_of(text.begin(), text.end(), [](char c) { return std::isdigit(c); });
  if (!digits || std::stoull(text) == 0) {
    return Status::InvalidArgument(what + " '" + text.substr(0, 40) +
                                   "' is not a positive decimal integer");
  }
  return std::stoull(text);
}

WebServer::WebServer(service::Core* core, const WebServerOptions& options)
    : core_(core),
      options_(options),
      loopback_(service::IsLoopbackAddress(options.address)),
      access_(core, options.auth),
      http_(std::make_unique<httplib::Server>()) {}

WebServer::~WebServer() { Stop(); }

StatusOr<std::unique_ptr<WebServer>> WebServer::Start(service::Core* core,
                                                      const WebServerOptions& options) {
  std::unique_ptr<WebServer> web(new WebServer(core, options));
  httplib::Server& http = *web->http_;
  http.new_task_queue = [] { return new httplib::ThreadPool(kThreads); };
  // An idle keep-alive connection holds a worker thread, and Stop() waits for
  // it to time out (httplib 0.11 checks for a stop only between requests):
  // an open page added up to the timeout to every mapd stop. So every answer
  // says "Connection: close" (below) and the browser closes the connection
  // itself. A short timeout instead races the browser's reuse of the
  // connection ("Failed to fetch"); this timeout only bounds clients that
  // ignore the header.
  http.set_keep_alive_timeout(1);
  http.set_read_timeout(10);
  // A client that stops reading holds a thread, and Stop(), this long at most.
  http.set_write_timeout(2);
  // httplib's default adds SO_REUSEPORT: a second server on a taken port
  // would then start and share its connections. Only SO_REUSEADDR (a restart
  // binds at once while old connections linger in TIME_WAIT).
  http.set_socket_options([](socket_t sock) {
    int yes = 1;
    setsockopt(sock, SOL_SOCKET, SO_REUSEADDR, &yes, sizeof yes);
  });
  web->Route();
  const std::string where = options.address + ":" + std::to_string(options.port);
  web->port_ = options.port == 0
                   ? http.bind_to_any_port(options.address)
                   : (http.bind_to_port(options.address, options.port) ? options.port : -1);
  if (web->port_ <= 0) {
    return Status::Unavailable("http.port " + std::to_string(options.port) +
                               ": the web view cannot listen on " + where +
                               " (the port is in use, or the address is not this machine's)");
  }
  web->thread_ = std::thread([w = web.get()] { w->http_->listen_after_bind(); });
  // httplib's stop() does nothing before its loop runs: wait for it, so
  // that a Stop() right after Start() is not lost.
  for (int i = 0; i < 5000 && !http.is_running(); ++i)
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  service::Log(service::LogLevel::kInfo, "web_listening",
               {{"address", options.address + ":" + std::to_string(web->port_)}});
  return web;
}

void WebServer::Stop() {
  if (stopping_.exchange(true)) return;
  http_->stop();
  if (thread_.joinable()) thread_.join();
}

void WebServer::Route() {
  using httplib::Request;
  using httplib::Response;
  // Requests a web page elsewhere could make the operator's browser send:
  // - a POST is refused unless it is JSON: a cross-site form can only send
  //   form or text bodies, and a cross-site script sending JSON must first
  //   pass a CORS preflight, which this server never grants;
  // - on a loopback port, a Host other than loopback is refused: a site whose
  //   name was rebound to 127.0.0.1 reads nothing (DNS rebinding).
  // One request per connection (see Start: an idle connection would hold Stop).
  http_->set_post_routing_handler(
      [](const Request&, Response& res) { res.set_header("Connection", "close"); });
  http_->set_pre_routing_handler([this](const Request& req, Response& res) {
    if (loopback_) {
      const std::string host = req.get_header_value("Host");
      if (!service::IsLoopbackHost(host)) {
        SendError(res, Status::PermissionDenied("Host '" + EscapeControlChars(host.substr(0, 100)) +
                                                "' is not this loopback web view; open it as "
                                                "http://127.0.0.1:<http.port>/"));
        return httplib::Server::HandlerResponse::Handled;
      }
    }
    if (req.method == "POST" &&
        req.get_header_value("Content-Type").rfind("application/json", 0) != 0) {
      SendError(res, Status::InvalidArgument("a POST must be sent as Content-Type: "
                                             "application/json (cross-site forms are refused)"));
      return httplib::Server::HandlerResponse::Handled;
    }
    return httplib::Server::HandlerResponse::Unhandled;
  });
  // Every route but the page checks the caller first (the page holds no data),
  // then finds the map it is about (?map=ID; absent: the default map).
  struct Admitted {
    service::Principal who;
    std::shared_ptr<service::Core> core;  // held until the request is answered
  };
  auto authenticate = [this](const Request& req) {
    const std::string* header =
        req.has_header("Authorization") ? &req.headers.find("Authorization")->second : nullptr;
    return access_.AuthenticateHeader(header,
                                      req.remote_addr + ":" + std::to_string(req.remote_port));
  };
  auto admit = [this, authenticate](const Request& req, Response& res,
                                    service::Permission permission,
                                    const std::string& action) -> StatusOr<Admitted> {
    StatusOr<service::Principal> who = authenticate(req);
    Status s = who.ok() ? access_.Check(*who, permission, action, "", "web") : who.status();
    const std::string map = req.has_param("map") ? req.get_param_value("map") : "default";
    std::shared_ptr<service::Core> core;
    if (s.ok()) s = access_.CheckMap(*who, map, action);
    if (s.ok()) {
      if (options_.find_map) {
        core = options_.find_map(map);
      } else if (map == "default") {
        core = std::shared_ptr<service::Core>(std::shared_ptr<void>(), core_);  // not owned
      }
      if (core == nullptr) {
        s = Status::NotFound("map '" + EscapeControlChars(map.substr(0, 128)) +
                             "' is not served here; /api/maps lists the maps");
      }
    }
    if (s.ok()) s = core->CheckReady();
    if (!s.ok()) {
      SendError(res, s);
      return s;
    }
    return Admitted{*who, core};
  };
  auto read = [admit](const Request& req, Response& res,
                      const char* action) -> std::shared_ptr<service::Core> {
    StatusOr<Admitted> a = admit(req, res, service::Permission::kReadMap, action);
    return a.ok() ? a->core : nullptr;
  };

  http_->Get("/", [](const Request&, Response& res) {
    res.set_content(kIndexHtml, "text/html; charset=utf-8");
  });
  http_->Get("/api/maps", [this, authenticate](const Request& req, Response& res) {
    StatusOr<service::Principal> who = authenticate(req);
    Status s = who.ok() ? access_.Check(*who, service::Permission::kReadMap, "ListMaps", "", "web")
                        : who.status();
    if (!s.ok()) return SendError(res, s);
    const std::vector<std::string> all =
        options_.list_maps ? options_.list_maps() : std::vector<std::string>{"default"};
    Json maps = Json::array();
    for (const std::string& id : all) {
      if (service::AuthorizeMap(*who, id, "ListMaps").ok()) maps.push_back(id);
    }
    SendJson(res, {{"maps", std::move(maps)}});
  });
  http_->Get("/api/features", [read](const Request& req, Response& res) {
    std::shared_ptr<service::Core> core = read(req, res, "GetFeatureMap");
    if (core == nullptr) return;
    uint64_t version = 0;
    std::vector<service::PlaneView> planes;
    const std::vector<service::FusedView> lines =
        core->QueryFeatures(service::FeatureQuery(), &version, &planes);
    SendJson(res, MapJson(version, lines, planes));
  });
  http_->Get("/api/events", [this, read](const Request& req, Response& res) {
    std::shared_ptr<service::Core> core = read(req, res, "WatchFeatureMap");
    if (core != nullptr) ServeEvents(std::move(core), req, res, &stopping_, &event_streams_);
  });
  http_->Get("/api/robots", [read](const Request& req, Response& res) {
    if (auto core = read(req, res, "ListRobots")) ServeRobots(core.get(), res);
  });
  http_->Get("/api/global-map.png", [read](const Request& req, Response& res) {
    if (auto core = read(req, res, "GetGlobalMap")) ServeGlobalMap(core.get(), res);
  });
  http_->Get("/metrics", [read](const Request& req, Response& res) {
    if (auto core = read(req, res, "GetStats"))
      res.set_content(MetricsText(*core), "text/plain; version=0.0.4; charset=utf-8");
  });
  http_->Get("/api/merges", [read](const Request& req, Response& res) {
    std::shared_ptr<service::Core> core = read(req, res, "ListMerges");
    if (core == nullptr) return;
    const std::string state = req.get_param_value("state");
    if (!state.empty() && state != "proposed" && state != "accepted" && state != "rejected" &&
        state != "refused") {
      SendError(res, Status::InvalidArgument("state '" + state.substr(0, 40) +
                                             "' is not proposed, accepted, rejected or refused"));
      return;
    }
    StatusOr<std::vector<storage::MergeRecord>> all = core->store().ListMerges();
    if (!all.ok()) return SendError(res, all.status());
    Json merges = Json::array();
    for (const storage::MergeRecord& r : *all) {
      if (state.empty() || state == storage::MergeStateName(r.state)) merges.push_back(ToJson(r));
    }
    SendJson(res, {{"merges", std::move(merges)}});
  });
  http_->Post(R"(/api/merges/([^/]*)/(approve|reject))", [admit](const Request& req,
                                                                 Response& res) {
    const bool approve = req.matches[2] == "approve";
    const char* action = approve ? "ApproveMerge" : "RejectMerge";
    StatusOr<Admitted> admitted = admit(req, res, service::Permission::kMerge, action);
    if (!admitted.ok()) return;
    service::Core* const core = admitted->core.get();
    StatusOr<uint64_t> id = ParseId(req.matches[1], "merge id");
    if (!id.ok()) return SendError(res, id.status());
    std::string reason;
    if (!approve) {
      const Json body = Json::parse(req.body, nullptr, /*allow_exceptions=*/false);
      if (body.is_object() && body.contains("reason") && body["reason"].is_string())
        reason = body["reason"].get<std::string>();
      if (Status s = service::CheckRejectReason(reason); !s.ok()) {
        return SendError(
            res, Status::InvalidArgument(s.message() + "; send a JSON body {\"reason\": \"...\"}"));
      }
    }
    const auto merge_id = static_cast<int64_t>(*id);
    if (Status s = service::DecideProposal(core, merge_id, reason, admitted->who); !s.ok())
      return SendError(res, s);
    StatusOr<storage::MergeRecord> r = core->store().GetMerge(merge_id);
    if (!r.ok()) return SendError(res, r.status());
    SendJson(res, ToJson(*r));
  });
  http_->set_error_handler([](const Request& req, Response& res) {
    if (!res.body.empty()) return;
    SendError(res, res.status == 404
                       ? Status::NotFound("no such page: " + req.path.substr(0, 100))
                       : Status::InvalidArgument("HTTP " + std::to_string(res.status)));
  });
}

}  // namespace mapd::web
