// A map's own settings (CreateMap, docs/scale-out.md): the "fusion.*",
// "planes.*" and "merge.*" keys of mapd's config file, over the server's
// settings for that map alone. An indoor site and an outdoor one may then fuse
// and merge differently in one mapd. They are stored beside the map's
// database, <id>.db -> <id>.conf, in the config file's `key = value` lines,
// and read each time the map is opened.
#ifndef MAPD_SERVICE_MAP_SETTINGS_H_
#define MAPD_SERVICE_MAP_SETTINGS_H_

#include <map>
#include <string>

#include "common/status.h"
#include "service/config.h"

namespace mapd::service {

using MapSettings = std::map<std::string, std::string>;  // key -> value

// `base` with `settings` applied, in *out. InvalidArgument naming the key
// when one is not a fusion., planes. or merge. setting, or its value (or the
// whole) is refused as a config file would be.
Status ApplyMapSettings(const MapSettings& settings, const ServerConfig& base, ServerConfig* out);

// "<dir>/site-7.db" -> "<dir>/site-7.conf".
std::string MapSettingsPath(const std::string& db_path);
// The settings stored at `path`; empty when there is no such file.
// InvalidArgument naming the file and line for a malformed one.
StatusOr<MapSettings> ReadMapSettings(const std::string& path);
// Writes `settings` to `path` owner-only, atomically (a temporary file renamed).
Status WriteMapSettings(const std::string& path, const MapSettings& settings);
// The same `key = value` lines as text (PostgreSQL keeps them in the map's
// row), and back; `name` says where the text is from in messages.
std::string MapSettingsText(const MapSettings& settings);
StatusOr<MapSettings> ParseMapSettings(const std::string& text, const std::string& name);

}  // namespace mapd::service

#endif  // MAPD_SERVICE_MAP_SETTINGS_H_
