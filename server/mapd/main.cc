// mapd: the multi-robot map server.
#include <CLI/CLI.hpp>
#include <csignal>
#include <cstdio>
#include <functional>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "service/config.h"
#include "service/config_settings.h"
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

// The command line, parsed by CLI11: every setting of the table in
// service/config_settings.cc is a flag --KEY VALUE whose --help shows the
// table's help and the default read from a default-constructed ServerConfig,
// so flags, config files, --help and --print-config cannot drift apart.
struct CommandLine {
  std::vector<std::string> config_files;  // read in order, before the flags
  bool print_config = false;
  bool version = false;
  std::vector<std::pair<std::string, std::string>> settings;  // (key, value) in command-line order
  std::function<int()> token;                                 // set by `mapd token ...`
};

void AddFlags(CLI::App* app, CommandLine* line) {
  using mapd::service::Setting;
  // A flag given twice: the later one wins (the container entrypoint passes its
  // defaults first, the user's flags after them). Subcommands inherit this.
  app->option_defaults()->multi_option_policy(CLI::MultiOptionPolicy::TakeLast);
  app->footer(
      "Every KEY may also be set in the config file as 'KEY = VALUE'; flags override the file.");
  app->add_option("--config", line->config_files, "read settings from FILE first")
      ->type_name("FILE")
      ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll);
  app->add_flag("--print-config", line->print_config,
                "print the settings in effect as a config file, and exit");
  app->add_flag("--version", line->version, "print the version and exit");
  const mapd::service::ServerConfig defaults;
  for (const Setting& s : mapd::service::Settings()) {
    app->add_option_function<std::string>(
           "--" + s.key,
           [line, key = s.key](const std::string& v) { line->settings.emplace_back(key, v); },
           s.help)
        ->type_name("<" + s.kind + ">")
        ->default_str(s.get(defaults));
  }
  mapd::AddTokenCommand(app, &line->token);
}

}  // namespace

int main(int argc, char** argv) {
  using mapd::service::ApplySetting;
  using mapd::service::ConfigFileText;
  using mapd::service::LoadConfigFile;
  using mapd::service::Log;
  using mapd::service::LogLevel;
  using mapd::service::MapServer;
  using mapd::service::ServerConfig;
  using mapd::service::SetLogLevel;
  CLI::App app("mapd: serves the mapserver.v1 gRPC API.", "mapd");
  CommandLine line;
  AddFlags(&app, &line);
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    std::fprintf(stderr, "mapd%s: %s (see 'mapd%s --help')\n",
                 app.got_subcommand("token") ? " token" : "", e.what(),
                 app.got_subcommand("token") ? " token" : "");
    return 2;
  }
  if (line.token) return line.token();  // offline token management (token_command.h)
  if (line.version) {
    std::printf("mapd %s\n", MAPD_VERSION);
    return 0;
  }
  // The config file first, so that flags override it wherever they stand.
  ServerConfig config;
  mapd::Status s = mapd::Status::Ok();
  for (size_t i = 0; i < line.config_files.size() && s.ok(); ++i)
    s = LoadConfigFile(line.config_files[i], &config);
  for (size_t i = 0; i < line.settings.size() && s.ok(); ++i) {
    s = ApplySetting(line.settings[i].first, line.settings[i].second, &config);
  }
  if (s.ok()) s = config.Validate();
  if (!s.ok()) {
    std::fprintf(stderr, "mapd: %s\n", s.message().c_str());
    return 2;
  }
  if (line.print_config) {
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
