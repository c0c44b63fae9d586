// mapd's command line, parsed by CLI11. Every setting of the table in
// service/config_settings.cc is a flag --KEY VALUE (or --KEY=VALUE) whose
// --help shows the table's help line and the default read from a
// default-constructed ServerConfig, so flags, config files, --help and
// --print-config cannot drift apart. `mapd token ...` (token_command.h) is a
// subcommand.
#ifndef MAPD_MAPD_COMMAND_LINE_H_
#define MAPD_MAPD_COMMAND_LINE_H_

#include <CLI/CLI.hpp>
#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "common/status.h"
#include "service/config.h"

namespace mapd {

struct CommandLine {
  std::vector<std::string> config_files;  // read in order, before the flags
  bool print_config = false;
  bool version = false;
  std::vector<std::pair<std::string, std::string>> settings;  // (key, value) in command-line order
  std::function<int()> offline;  // set by `mapd token ...` and `mapd migrate ...`
};

// Adds every flag and the token subcommand to `app`; parsing fills `*line`.
void AddFlags(CLI::App* app, CommandLine* line);

// The config files first, then the setting flags (so flags override the file
// wherever they stand), then ServerConfig::Validate. InvalidArgument names
// the setting (and the file and line).
Status ApplyCommandLine(const CommandLine& line, service::ServerConfig* config);

}  // namespace mapd

#endif  // MAPD_MAPD_COMMAND_LINE_H_
