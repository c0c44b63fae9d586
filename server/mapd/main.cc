// mapd: the multi-robot map server.
#include <csignal>
#include <cstdio>
#include <string>
#include <thread>
#include <vector>

#include "service/config.h"
#include "service/log.h"
#include "service/server.h"
#include "token_command.h"

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
  using namespace mapd::service;
  // `mapd token ...`: offline token management (token_command.h).
  if (argc > 1 && std::string(argv[1]) == "token") {
    return mapd::RunTokenCommand(std::vector<std::string>(argv + 2, argv + argc));
  }
  ServerConfig config;
  FlagAction action = FlagAction::kServe;
  mapd::Status s = ParseFlags(std::vector<std::string>(argv + 1, argv + argc), &config, &action);
  if (action == FlagAction::kHelp) {
    std::fputs(FlagsHelp().c_str(), stdout);
    std::fputs("\nmapd token create|list|revoke --db FILE ...: manage tokens offline (mapd token --help;\n"
               "docs/security.md)\n", stdout);
    return 0;
  }
  if (action == FlagAction::kVersion) {
    std::printf("mapd %s\n", MAPD_VERSION);
    return 0;
  }
  if (!s.ok()) {
    std::fprintf(stderr, "mapd: %s\n", s.message().c_str());
    return 2;
  }
  if (action == FlagAction::kPrintConfig) {
    std::fputs(ConfigFileText(config).c_str(), stdout);
    return 0;
  }
  SetLogLevel(ParseLevel(config.log_level));

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
  std::thread waiter([&signals, srv = server->get()] {
    int sig = 0;
    sigwait(&signals, &sig);
    Log(LogLevel::kInfo, "signal", {{"signal", sig == SIGTERM ? "SIGTERM" : "SIGINT"}});
    srv->Shutdown();
  });
  (*server)->Wait();
  waiter.join();
  server->reset();
  return 0;
}
