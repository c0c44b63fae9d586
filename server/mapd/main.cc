// mapd: the multi-robot map server.
#include <sys/stat.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "mapd/command_line.h"
#include "service/config.h"
#include "service/log.h"
#include "service/server.h"
#include "web/web_server.h"

namespace {

mapd::service::LogLevel ParseLevel(const std::string& s) {
  using mapd::service::LogLevel;
  if (s == "debug") return LogLevel::kDebug;
  if (s == "warn") return LogLevel::kWarn;
  if (s == "error") return LogLevel::kError;
  return LogLevel::kInfo;
}

}  // namespace

int main(int argc, char** argv) {
  using mapd::service::ConfigFileText;
  using mapd::service::Log;
  using mapd::service::LogLevel;
  using mapd::service::MapServer;
  using mapd::service::ServerConfig;
  using mapd::service::SetLogLevel;
  // Everything mapd creates (the database, its -wal and -shm, the default
  // path's directory, snapshots' temporary files) is the owner's only: the
  // database holds the token hashes (docs/security.md, "Files").
  umask(077);
  CLI::App app("mapd: serves the mapserver.v1 gRPC API.", "mapd");
  mapd::CommandLine line;
  mapd::AddFlags(&app, &line);
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    std::string command;  // " token", " migrate" or ""
    for (const char* name : {"token", "migrate"})
      if (app.got_subcommand(name)) command = std::string(" ") + name;
    std::fprintf(stderr, "mapd%s: %s (see 'mapd%s --help')\n", command.c_str(), e.what(),
                 command.c_str());
    return 2;
  }
  // Offline work on the database: token management (token_command.h), moving
  // a map (migrate_command.h).
  if (line.offline) return line.offline();
  if (line.version) {
    std::printf("mapd %s\n", MAPD_VERSION);
    return 0;
  }
  ServerConfig config;
  const mapd::Status s = mapd::ApplyCommandLine(line, &config);
  if (!s.ok()) {
    std::fprintf(stderr, "mapd: %s\n", s.message().c_str());
    return 2;
  }
  if (line.print_config) {
    std::fputs(ConfigFileText(config).c_str(), stdout);
    return 0;
  }
  SetLogLevel(ParseLevel(config.log_level));
  // Tests only (tests/service/mapd_process_test.cc): while this file exists
  // the fuser waits, recovery included, so that a test can look at a
  // recovering mapd on a machine of any speed. Logged, so that it is never
  // on unnoticed.
  if (const char* hold = std::getenv("MAPD_TEST_HOLD_FUSER_FILE"); hold != nullptr && *hold) {
    const std::string path = hold;
    config.hold_fuser_for_test = [path] { return access(path.c_str(), F_OK) == 0; };
    Log(LogLevel::kWarn, "fuser_held_for_test", {{"while_exists", path}});
  }

  // SIGTERM/SIGINT are taken by one thread with sigwait: no work in a signal handler.
  sigset_t signals;
  sigemptyset(&signals);
  sigaddset(&signals, SIGTERM);
  sigaddset(&signals, SIGINT);
  pthread_sigmask(SIG_BLOCK, &signals, nullptr);
  std::signal(SIGPIPE, SIG_IGN);

  mapd::StatusOr<std::unique_ptr<MapServer>> server = MapServer::Start(config);
  if (!server.ok()) {
    std::fprintf(stderr, "mapd: %s\n", server.status().ToString().c_str());
    return 1;
  }
  // The web view (http.port; off by default) beside the gRPC server.
  std::unique_ptr<mapd::web::WebServer> web;
  if (config.web.port != 0) {
    mapd::web::WebServerOptions options;
    options.address = config.web.address;
    options.port = config.web.port;
    options.auth = (*server)->auth();
    const mapd::service::MapDirectory* maps = &(*server)->maps();
    options.list_maps = [maps] { return maps->Ids(); };
    options.find_map = [maps](const std::string& id) { return maps->FindCore(id); };
    mapd::StatusOr<std::unique_ptr<mapd::web::WebServer>> started =
        mapd::web::WebServer::Start((*server)->core(), options);
    if (!started.ok()) {
      std::fprintf(stderr, "mapd: %s\n", started.status().ToString().c_str());
      (*server)->Shutdown();
      (*server)->Wait();
      return 1;
    }
    web = std::move(started).value();
  }
  std::thread waiter([&signals, &web, srv = server->get()] {
    int sig = 0;
    sigwait(&signals, &sig);
    Log(LogLevel::kInfo, "signal", {{"signal", sig == SIGTERM ? "SIGTERM" : "SIGINT"}});
    if (web) web->Stop();  // event streams end, no new requests
    srv->Shutdown();
  });
  (*server)->Wait();
  waiter.join();
  web.reset();
  server->reset();
  return 0;
}
