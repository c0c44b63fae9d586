// The table of mapd's settings: for each one its key, the kind of value it
// takes, its help text (with the unit), how it is parsed and range-checked,
// and how its current value is written. Flags, config files, --help,
// --print-config and deploy/mapd.conf.example all come from this one table,
// and the defaults it shows are read from a default-constructed ServerConfig,
// so no default is written twice.
#ifndef MAPD_SERVICE_CONFIG_SETTINGS_H_
#define MAPD_SERVICE_CONFIG_SETTINGS_H_

#include <functional>
#include <string>
#include <vector>

#include "common/status.h"
#include "service/config.h"

namespace mapd::service {

struct Setting {
  std::string key;
  std::string kind;  // "number", "integer", "bool", "text", or the choices "a|b"
  std::string help;  // one line: what it does, its unit and range
  // Parses `value`, checks its range, stores it; InvalidArgument names the key.
  std::function<Status(const std::string& value, ServerConfig* config)> set;
  // Checks the value held by `config` (a config built in code, not parsed).
  std::function<Status(const ServerConfig& config)> check;
  // The value held by `config`, as a config-file line writes it.
  std::function<std::string(const ServerConfig& config)> get;
};

// In the order --help and the example file show them.
const std::vector<Setting>& Settings();

}  // namespace mapd::service

#endif  // MAPD_SERVICE_CONFIG_SETTINGS_H_
