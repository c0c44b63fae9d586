// mapctl: the command-line client of mapd.
//
//   mapctl [--server HOST:PORT] [--map ID] [--timeout S] [--token T] [--tls-ca PEM
//          [--tls-cert PEM --tls-key PEM]] <command> [options]
//
// Exit codes: 0 ok; 1 the server answered an error (or batches were rejected);
// 2 usage error; 3 the server could not be reached. Errors are one line on
// stderr: `mapctl: <what failed>: <server message> (<CODE>)`.
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>
#include <tuple>
#include <vector>

#include "client/cli.h"
#include "client/commands.h"

namespace {

bool ReadPem(const std::string& path, std::string* out) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return false;
  std::ostringstream s;
  s << in.rdbuf();
  *out = s.str();
  return true;
}

}  // namespace

int main(int argc, char** argv) {
  using mapd::client::Action;
  using mapd::client::Context;
  using mapd::client::kContinue;
  using mapd::client::UsageError;
  Context ctx;
  const char* env_server = std::getenv("MAPD_SERVER");
  ctx.server = env_server != nullptr && *env_server != '\0' ? env_server : "127.0.0.1:50051";
  if (const char* t = std::getenv("MAPD_TOKEN"); t != nullptr) ctx.token = t;
  if (const char* m = std::getenv("MAPD_MAP"); m != nullptr) ctx.map = m;
  std::string tls_ca, tls_cert, tls_key;  // PEM file names

  // Global flags come before the command; each command's flags after it.
  CLI::App app("The command-line client of the mapd map server.", "mapctl");
  app.require_subcommand(1);
  // A flag given twice: the later one wins, as scripts that append overrides expect
  // (subcommands inherit this).
  app.option_defaults()->multi_option_policy(CLI::MultiOptionPolicy::TakeLast);
  app.add_option("--server", ctx.server,
                 "HOST:PORT of mapd (default $MAPD_SERVER, else 127.0.0.1:50051); several, "
                 "comma-separated, for mapd instances sharing one database: mapctl finds the one "
                 "serving --map, and robot streams fail over between them");
  app.set_version_flag("--version", std::string("mapctl ") + MAPD_VERSION);
  app.add_option("--timeout", ctx.timeout_s, "seconds to wait for an answer")
      ->capture_default_str()
      ->check(mapd::client::PositiveReal());
  app.add_option("--token", ctx.token, "bearer token (default $MAPD_TOKEN; docs/security.md)");
  app.add_option("--map", ctx.map,
                 "the map to work on, when mapd serves several (default $MAPD_MAP, else the "
                 "server's default map; 'mapctl maps' lists them)");
  CLI::Option* ca = app.add_option("--tls-ca", tls_ca,
                                   "use TLS, trusting this CA (PEM) for the server's certificate");
  CLI::Option* cert =
      app.add_option("--tls-cert", tls_cert, "client certificate (PEM) for mTLS")->needs(ca);
  CLI::Option* key = app.add_option("--tls-key", tls_key, "its private key (PEM)")->needs(ca);
  cert->needs(key);
  key->needs(cert);
  app.footer(
      "'mapctl <command> --help' for each command.\n"
      "Exit codes: 0 ok, 1 the server answered an error or batches were rejected,\n"
      "2 usage error, 3 the server could not be reached.");

  Action action;
  mapd::client::AddMapCommands(&app, &action);
  mapd::client::AddWatchCommand(&app, &action);
  mapd::client::AddIngestCommands(&app, &action);
  mapd::client::AddReplayCommand(&app, &action);
  mapd::client::AddSubmapCommands(&app, &action);
  mapd::client::AddMergeCommands(&app, &action);
  mapd::client::AddExportCommands(&app, &action);
  mapd::client::AddRenderCommand(&app, &action);
  mapd::client::AddAuthCommands(&app, &action);
  // Moving a map between stores works on the databases, not through the
  // API, so it is `mapd migrate`; whoever looks for it here is told so
  // rather than "argument not expected". Hidden from the command list.
  CLI::App* migrate = app.add_subcommand("migrate", "see `mapd migrate --help`");
  migrate->group("");
  migrate->allow_extras();
  migrate->callback([&action] {
    action = [](const mapd::client::Context&) {
      return UsageError("migrate",
                        "moving a map between stores is `mapd migrate` (run beside the "
                        "databases, with the map's mapd stopped; docs/scale-out.md): mapctl "
                        "speaks only the API");
    };
  });
  if (int rc = mapd::client::ParseCommandLine(&app, argc, argv); rc != kContinue) return rc;
  for (size_t start = 0;;) {  // several servers: instances of one database
    const size_t comma = ctx.server.find(',', start);
    ctx.servers.push_back(ctx.server.substr(start, comma - start));
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  for (const std::string& server : ctx.servers) {
    if (std::string problem = mapd::client::ServerAddressProblem(server); !problem.empty()) {
      std::string what = "server '";
      what.append(server).append("' (--server or $MAPD_SERVER): ").append(problem);
      return UsageError("", what);
    }
  }

  // The channel connects lazily, on the first call: --help needs no server.
  // A restarted server is found again within 2 s, a frozen one noticed in
  // about 8 s (robot::RobotChannelArguments).
  const grpc::ChannelArguments channel_args = mapd::robot::RobotChannelArguments();
  std::shared_ptr<grpc::ChannelCredentials> credentials = grpc::InsecureChannelCredentials();
  if (!tls_ca.empty()) {
    grpc::SslCredentialsOptions ssl;
    for (auto& [flag, file, target] : {std::tuple{"--tls-ca", &tls_ca, &ssl.pem_root_certs},
                                       std::tuple{"--tls-cert", &tls_cert, &ssl.pem_cert_chain},
                                       std::tuple{"--tls-key", &tls_key, &ssl.pem_private_key}}) {
      if (!file->empty() && !ReadPem(*file, target)) {
        return UsageError("", std::string(flag) + ": cannot read '" + *file + "'");
      }
    }
    credentials = grpc::SslCredentials(ssl);
  }
  ctx.connect = [credentials, channel_args](const std::string& address) {
    return grpc::CreateCustomChannel(address, credentials, channel_args);
  };
  ctx.channel = ctx.connect(ctx.servers[0]);
  ctx.stub = mapserver::v1::MapService::NewStub(ctx.channel);
  return action(ctx);
}
