// mapd-health: asks a running mapd for grpc.health.v1.Health/Check (the
// server's overall status, or one map's with --map) and turns the answer into
// an exit code, for container HEALTHCHECKs and service monitors.
//
//   mapd-health [--server HOST:PORT] [--map ID] [--timeout S] [--tls-ca PEM [--tls-name NAME]]
//
// Exit codes: 0 SERVING; 1 NOT_SERVING (e.g. still replaying its fusion
// snapshot) or UNKNOWN; 2 usage error; 3 unreachable or the call failed
// (a map the server does not serve: NOT_FOUND).
// The health service answers without credentials, so the probe needs no token.
#include <CLI/CLI.hpp>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <string>

#include "mapd/health_check.h"

int main(int argc, char** argv) {
  std::string server = "127.0.0.1:50051", ca_path, tls_name, map;
  double timeout_s = 5.0;
  CLI::App app(
      "mapd-health: the health of a running mapd, as an exit code (0 SERVING, 1 not, "
      "2 usage, 3 unreachable).",
      "mapd-health");
  app.add_option("--server", server, "HOST:PORT of mapd")->capture_default_str();
  app.add_option("--map", map,
                 "one map's health (service map/ID) instead of the server's (every map's)");
  app.add_option("--timeout", timeout_s, "seconds to wait for the answer")
      ->check(CLI::Range(0.001, 3600.0))
      ->capture_default_str();
  CLI::Option* ca =
      app.add_option("--tls-ca", ca_path, "PEM file of the CA that signed mapd's certificate");
  app.add_option("--tls-name", tls_name,
                 "the name mapd's certificate carries (when dialling another)")
      ->needs(ca);
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    std::fprintf(stderr, "mapd-health: %s (see 'mapd-health --help')\n", e.what());
    return 2;
  }

  std::shared_ptr<grpc::ChannelCredentials> credentials = grpc::InsecureChannelCredentials();
  grpc::ChannelArguments args;
  if (!ca_path.empty()) {
    std::ifstream in(ca_path, std::ios::binary);
    if (!in) {
      std::fprintf(stderr, "mapd-health: cannot read --tls-ca '%s'\n", ca_path.c_str());
      return 2;
    }
    std::ostringstream pem;
    pem << in.rdbuf();
    grpc::SslCredentialsOptions ssl;
    ssl.pem_root_certs = pem.str();
    credentials = grpc::SslCredentials(ssl);
    // Dialling 127.0.0.1 while the certificate names the public host.
    if (!tls_name.empty()) args.SetSslTargetNameOverride(tls_name);
  }
  mapd::ServingStatus serving = mapd::ServingStatus::kUnknown;
  const grpc::Status status =
      mapd::CheckHealth(grpc::CreateCustomChannel(server, credentials, args),
                        std::chrono::milliseconds(static_cast<long>(timeout_s * 1000)), &serving,
                        map.empty() ? "" : "map/" + map);
  if (!status.ok()) {
    std::fprintf(stderr, "mapd-health: %s: %s (code %d)\n", server.c_str(),
                 status.error_message().c_str(), static_cast<int>(status.error_code()));
    return 3;
  }
  std::printf("%s%s %s\n", server.c_str(), map.empty() ? "" : (" map " + map).c_str(),
              mapd::ServingStatusName(serving));
  return serving == mapd::ServingStatus::kServing ? 0 : 1;
}
