#include "client/cli.h"

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>

#include "client/robot/robot_client.h"
#include "client/text_util.h"

namespace mapd::client {

namespace pb = mapserver::v1;

std::unique_ptr<grpc::ClientContext> Context::NewCallContext() const {
  auto context = NewStreamContext();
  context->set_deadline(std::chrono::system_clock::now() + timeout());
  return context;
}

std::unique_ptr<grpc::ClientContext> Context::NewStreamContext() const {
  PrepareMapOnce();
  auto context = std::make_unique<grpc::ClientContext>();
  if (!token.empty()) context->AddMetadata("authorization", "Bearer " + token);
  if (!map.empty()) context->AddMetadata("mapd-map-id", map);
  return context;
}

void Context::Use(const std::string& address) const {
  channel = connect(address);
  stub = pb::MapService::NewStub(channel);
}

void Context::PrepareMapOnce() const {
  std::call_once(*map_checked_, [this] {
    // Where the map is served: asked of each server given until one answers.
    // A server from before LocateMap (UNIMPLEMENTED) serves its maps itself.
    for (size_t i = 0; connect && i < servers.size(); ++i) {
      if (i > 0) Use(servers[i]);
      pb::LocateMapRequest request;
      request.set_map_id(map);
      pb::MapLocation where;
      auto call = NewServerCallContext();
      call->set_deadline(std::chrono::system_clock::now() +
                         std::min(timeout(), std::chrono::milliseconds(3000)));
      const grpc::Status s = stub->LocateMap(call.get(), request, &where);
      if (s.error_code() == grpc::StatusCode::UNAVAILABLE && i + 1 < servers.size()) continue;
      if (s.ok() && !where.here() && !where.address().empty()) Use(where.address());
      if (!s.ok() && i > 0) Use(servers[0]);  // report the first server's error
      break;
    }
    if (map.empty() || map == "default") return;  // every server serves that one
    const grpc::Status s = robot::CheckMapServed(stub.get(), NewServerCallContext().get(), map);
    if (s.ok()) return;
    if (s.error_code() == grpc::StatusCode::UNAVAILABLE) {
      std::exit(ReportRpcError(*this, "--map " + map, s));
    }
    PrintError("--map " + map + ": " + s.error_message() + " (" + StatusCodeName(s.error_code()) +
               ")");
    std::exit(kExitFailed);
  });
}

robot::RobotClientOptions Context::RobotOptions() const {
  PrepareMapOnce();
  robot::RobotClientOptions options;
  options.give_up_after = timeout();
  options.token = token;
  options.map_id = map;
  options.connect = connect;
  for (size_t i = 1; i < servers.size(); ++i) options.addresses.push_back(servers[i]);
  return options;
}

std::unique_ptr<grpc::ClientContext> Context::NewServerCallContext() const {
  auto context = std::make_unique<grpc::ClientContext>();
  context->set_deadline(std::chrono::system_clock::now() + timeout());
  if (!token.empty()) context->AddMetadata("authorization", "Bearer " + token);
  return context;
}

std::chrono::milliseconds Context::timeout() const {
  return std::chrono::milliseconds(static_cast<int64_t>(timeout_s * 1000));
}

const char* StatusCodeName(grpc::StatusCode code) {
  switch (code) {
    case grpc::StatusCode::OK:
      return "OK";
    case grpc::StatusCode::CANCELLED:
      return "CANCELLED";
    case grpc::StatusCode::UNKNOWN:
      return "UNKNOWN";
    case grpc::StatusCode::INVALID_ARGUMENT:
      return "INVALID_ARGUMENT";
    case grpc::StatusCode::DEADLINE_EXCEEDED:
      return "DEADLINE_EXCEEDED";
    case grpc::StatusCode::NOT_FOUND:
      return "NOT_FOUND";
    case grpc::StatusCode::ALREADY_EXISTS:
      return "ALREADY_EXISTS";
    case grpc::StatusCode::PERMISSION_DENIED:
      return "PERMISSION_DENIED";
    case grpc::StatusCode::RESOURCE_EXHAUSTED:
      return "RESOURCE_EXHAUSTED";
    case grpc::StatusCode::FAILED_PRECONDITION:
      return "FAILED_PRECONDITION";
    case grpc::StatusCode::ABORTED:
      return "ABORTED";
    case grpc::StatusCode::OUT_OF_RANGE:
      return "OUT_OF_RANGE";
    case grpc::StatusCode::UNIMPLEMENTED:
      return "UNIMPLEMENTED";
    case grpc::StatusCode::INTERNAL:
      return "INTERNAL";
    case grpc::StatusCode::UNAVAILABLE:
      return "UNAVAILABLE";
    case grpc::StatusCode::DATA_LOSS:
      return "DATA_LOSS";
    case grpc::StatusCode::UNAUTHENTICATED:
      return "UNAUTHENTICATED";
    default:
      return "UNKNOWN";
  }
}

void PrintError(const std::string& message) {
  std::fprintf(stderr, "mapctl: %s\n", Visible(message).c_str());
}

int ReportRpcError(const Context& ctx, const std::string& what, const grpc::Status& status) {
  // A deadline is "unreachable" only if the channel never got connected.
  const bool unreachable =
      status.error_code() == grpc::StatusCode::UNAVAILABLE ||
      (status.error_code() == grpc::StatusCode::DEADLINE_EXCEEDED && ctx.channel != nullptr &&
       ctx.channel->GetState(false) != GRPC_CHANNEL_READY);
  std::string message = status.error_message();
  for (char& c : message) {
    if (c == '\n') c = ' ';
  }
  message = Visible(message);
  const std::string prefix =
      unreachable ? "cannot reach mapd at " + ctx.server + ": " + what : what;
  std::fprintf(stderr, "mapctl: %s: %s (%s)\n", prefix.c_str(), message.c_str(),
               StatusCodeName(status.error_code()));
  return unreachable ? kExitUnreachable : kExitFailed;
}

int UsageError(const std::string& command, const std::string& message) {
  std::fprintf(stderr, "mapctl%s%s: %s (see 'mapctl %s--help')\n", command.empty() ? "" : " ",
               command.c_str(), message.c_str(), command.empty() ? "" : (command + " ").c_str());
  return kExitUsage;
}

int CheckReachable(const Context& ctx, const std::string& what) {
  pb::Stats stats;
  auto call = ctx.NewCallContext();
  const grpc::Status status = ctx.stub->GetStats(call.get(), pb::GetStatsRequest(), &stats);
  return status.ok() ? kExitOk : ReportRpcError(ctx, what, status);
}

CLI::Validator PositiveReal() {
  return CLI::Validator(
      [](std::string& text) {
        double v = 0;
        return ParseDouble(text, &v) && v > 0 ? std::string()
                                              : "wants a number > 0, got '" + text + "'";
      },
      "> 0");
}

CLI::Validator PositiveId() {
  return CLI::Validator(
      [](std::string& text) {
        const bool digits =
            !text.empty() && text.find_first_not_of("0123456789") == std::string::npos;
        errno = 0;
        const bool ok = digits && std::strtoull(text.c_str(), nullptr, 10) > 0 && errno == 0;
        return ok ? std::string() : "'" + text + "' is not an id (a whole number > 0)";
      },
      "ID");
}

std::string ServerAddressProblem(const std::string& address) {
  // gRPC target URIs (unix:/path, dns:///host:port) are passed as they are.
  if (address.rfind("unix:", 0) == 0 || address.find(":///") != std::string::npos) return "";
  const size_t colon = address.rfind(':');
  if (address.empty() || colon == std::string::npos || colon == 0) {
    return "wants HOST:PORT (e.g. 127.0.0.1:50051)";
  }
  const std::string port = address.substr(colon + 1);
  if (port.empty() || port.size() > 5 ||
      port.find_first_not_of("0123456789") != std::string::npos || std::stoul(port) == 0 ||
      std::stoul(port) > 65535) {
    return "the port '" + port + "' is not a number in 1..65535 (HOST:PORT)";
  }
  return "";
}

int ParseCommandLine(CLI::App* app, int argc, const char* const* argv) {
  try {
    app->parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    // `mapctl nonsense --help` printed the top-level help and exited 0.
    if (app->get_subcommands().empty()) {
      for (int i = 1; i < argc; ++i) {
        const std::string arg = argv[i];
        if (arg.rfind("-", 0) == 0) {
          const CLI::Option* opt =
              arg.find('=') == std::string::npos ? app->get_option_no_throw(arg) : nullptr;
          if (opt != nullptr && opt->get_type_size() != 0) ++i;  // its value
          continue;
        }
        if (app->get_subcommands([&arg](CLI::App* c) { return c->check_name(arg); }).empty()) {
          return UsageError("", "unknown command '" + arg + "'");
        }
        break;
      }
    }
    return app->exit(e);  // the help of the (sub)command asked about, on stdout, exit 0
  } catch (const CLI::CallForVersion& e) {
    return app->exit(e);  // the version on stdout, exit 0
  } catch (const CLI::ParseError& e) {
    if (app->get_subcommands().empty() && !app->remaining().empty()) {
      return UsageError("", "unknown command '" + app->remaining().front() + "'");
    }
    // The deepest command reached names the help to see: "token create".
    std::string command;
    for (const CLI::App* c = app; !c->get_subcommands().empty();) {
      c = c->get_subcommands().front();
      command += (command.empty() ? "" : " ") + c->get_name();
    }
    return UsageError(command, e.what());
  }
  return kContinue;
}

bool ParseDouble(const std::string& s, double* out) {
  if (s.empty()) return false;
  char* end = nullptr;
  errno = 0;
  const double v = std::strtod(s.c_str(), &end);
  if (errno != 0 || end != s.c_str() + s.size() || !std::isfinite(v)) return false;
  *out = v;
  return true;
}

std::vector<std::string> Split(const std::string& s, char sep) {
  std::vector<std::string> out(1);
  for (char c : s) {
    if (c == sep)
      out.emplace_back();
    else
      out.back().push_back(c);
  }
  return out;
}

bool WriteOutput(const std::string& path, const std::string& data, std::string* error) {
  if (path == "-") {
    if (std::fwrite(data.data(), 1, data.size(), stdout) != data.size() ||
        std::fflush(stdout) != 0) {
      *error = "cannot write to stdout";
      return false;
    }
    return true;
  }
  const std::string tmp = path + ".part";
  {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    if (!out) {
      *error = "cannot open " + tmp + ": " + std::strerror(errno);
      return false;
    }
    out.write(data.data(), static_cast<std::streamsize>(data.size()));
    out.close();
    if (!out) {
      *error = "cannot write " + tmp + ": " + std::strerror(errno);
      std::remove(tmp.c_str());
      return false;
    }
  }
  if (std::rename(tmp.c_str(), path.c_str()) != 0) {
    *error = "cannot rename " + tmp + " to " + path + ": " + std::strerror(errno);
    std::remove(tmp.c_str());
    return false;
  }
  return true;
}

}  // namespace mapd::client
