// mapctl: the command-line client of mapd.
//
//   mapctl [--server HOST:PORT] [--timeout S] [--token T] [--tls-ca PEM
//          [--tls-cert PEM --tls-key PEM]] <command> [options]
//
// Exit codes: 0 ok; 1 the server answered an error (or batches were rejected);
// 2 usage error; 3 the server could not be reached. Errors are one line on
// stderr: `mapctl: <what failed>: <server message> (<CODE>)`.
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "client/cli.h"
#include "client/commands.h"

namespace {

using mapd::client::CommandArgs;
using mapd::client::Context;

struct Command {
  const char* name;
  int (*run)(const Context&, const CommandArgs&);
  const char* summary;
};

const Command kCommands[] = {
    {"status", mapd::client::RunStatus, "server statistics"},
    {"robots", mapd::client::RunRobots, "the robots seen, with their sessions and counts"},
    {"features", mapd::client::RunFeatures, "query / export the fused map (table, json, geojson, svg)"},
    {"ingest", mapd::client::RunIngest, "stream observation batches from a JSON-lines file"},
    {"simulate", mapd::client::RunSimulate, "stream (or export) simulated robots' laser lines"},
    {"submaps", mapd::client::RunSubmaps, "list stored voxel submaps"},
    {"submap", mapd::client::RunSubmap, "submap upload FILE --robot R: upload an OctoMap file"},
    {"merge", mapd::client::RunMerge, "merge two or more submaps (--wait: progress, --render: picture)"},
    {"global-map", mapd::client::RunGlobalMap, "download the merged global map (-o FILE.bt, --render)"},
    {"render", mapd::client::RunRender, "draw OctoMap files from above as PNG or SVG (no server needed)"},
    {"token", mapd::client::RunToken, "token create|list|revoke: manage bearer tokens (admin)"},
    {"audit", mapd::client::RunAudit, "the audit log, newest first (operator, admin)"},
    {"whoami", mapd::client::RunWhoAmI, "who the server takes this caller for"},
};

bool ReadPem(const std::string& path, std::string* out) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return false;
  std::ostringstream s;
  s << in.rdbuf();
  *out = s.str();
  return true;
}

void PrintHelp() {
  std::printf(
      "Usage: mapctl [--server HOST:PORT] [--timeout S] <command> [options]\n"
      "The command-line client of the mapd map server.\n\n"
      "  --server HOST:PORT  default $MAPD_SERVER, else 127.0.0.1:50051\n"
      "  --timeout S         seconds to wait for an answer (default 10)\n"
      "  --token T           bearer token (default $MAPD_TOKEN; docs/security.md)\n"
      "  --tls-ca PEM        use TLS, trusting this CA for the server's certificate\n"
      "  --tls-cert PEM      client certificate for mTLS (with --tls-key; needs --tls-ca)\n"
      "  --tls-key PEM       its private key\n\n"
      "Commands ('mapctl <command> --help' for each):\n");
  for (const Command& c : kCommands) std::printf("  %-12s %s\n", c.name, c.summary);
  std::printf(
      "\nExit codes: 0 ok, 1 the server answered an error or batches were rejected,\n"
      "2 usage error, 3 the server could not be reached.\n");
}

}  // namespace

int main(int argc, char** argv) {
  using namespace mapd::client;
  const std::vector<std::string> args(argv + 1, argv + argc);
  Context ctx;
  const char* env_server = std::getenv("MAPD_SERVER");
  ctx.server = env_server != nullptr && *env_server != '\0' ? env_server : "127.0.0.1:50051";
  if (const char* t = std::getenv("MAPD_TOKEN"); t != nullptr) ctx.token = t;
  std::map<std::string, std::string> tls;  // --tls-ca, --tls-cert, --tls-key: file names

  // Global flags come before the command.
  size_t i = 0;
  for (; i < args.size() && !args[i].empty() && args[i][0] == '-'; ++i) {
    const std::string& arg = args[i];
    const size_t eq = arg.find('=');
    const std::string name = arg.substr(0, eq);
    if (name == "--help" || name == "-h") {
      PrintHelp();
      return kExitOk;
    }
    if (name != "--server" && name != "--timeout" && name != "--token" && name.rfind("--tls-", 0) != 0) {
      return UsageError("", "unknown flag '" + name + "'");
    }
    std::string value;
    if (eq != std::string::npos) {
      value = arg.substr(eq + 1);
    } else if (i + 1 < args.size()) {
      value = args[++i];
    } else {
      return UsageError("", "flag " + name + " needs a value");
    }
    if (name == "--token") {
      ctx.token = value;
    } else if (name == "--tls-ca" || name == "--tls-cert" || name == "--tls-key") {
      tls[name] = value;
    } else if (name.rfind("--tls-", 0) == 0) {
      return UsageError("", "unknown flag '" + name + "'");
    } else if (name == "--server") {
      if (value.empty()) return UsageError("", "--server wants HOST:PORT");
      ctx.server = value;
    } else if (!ParseDouble(value, &ctx.timeout_s) || ctx.timeout_s <= 0) {
      return UsageError("", "--timeout wants a positive number of seconds, got '" + value + "'");
    }
  }
  if (i == args.size()) return UsageError("", "no command given");
  const std::string name = args[i];
  const Command* command = nullptr;
  for (const Command& c : kCommands) {
    if (name == c.name) command = &c;
  }
  if (command == nullptr) return UsageError("", "unknown command '" + name + "'");

  // The channel connects lazily, on the first call: --help needs no server.
  // A restarted server is found again within 2 s (gRPC's default backoff grows to 120 s).
  grpc::ChannelArguments channel_args;
  channel_args.SetInt(GRPC_ARG_INITIAL_RECONNECT_BACKOFF_MS, 200);
  channel_args.SetInt(GRPC_ARG_MIN_RECONNECT_BACKOFF_MS, 200);
  channel_args.SetInt(GRPC_ARG_MAX_RECONNECT_BACKOFF_MS, 2000);
  std::shared_ptr<grpc::ChannelCredentials> credentials = grpc::InsecureChannelCredentials();
  if (tls.count("--tls-cert") != tls.count("--tls-key")) return UsageError("", "--tls-cert and --tls-key go together");
  if (!tls.empty()) {
    if (!tls.count("--tls-ca")) return UsageError("", "--tls-cert needs --tls-ca (the CA of the server's certificate)");
    grpc::SslCredentialsOptions ssl;
    for (auto& [flag, target] : std::map<std::string, std::string*>{
             {"--tls-ca", &ssl.pem_root_certs}, {"--tls-cert", &ssl.pem_cert_chain}, {"--tls-key", &ssl.pem_private_key}}) {
      if (tls.count(flag) && !ReadPem(tls[flag], target)) return UsageError("", flag + ": cannot read '" + tls[flag] + "'");
    }
    credentials = grpc::SslCredentials(ssl);
  }
  ctx.channel = grpc::CreateCustomChannel(ctx.server, credentials, channel_args);
  ctx.stub = mapserver::v1::MapService::NewStub(ctx.channel);
  return command->run(ctx, CommandArgs(args.begin() + static_cast<long>(i) + 1, args.end()));
}
