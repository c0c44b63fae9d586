#include "service/map_settings.h"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>

namespace mapd::service {
namespace {

bool IsMapSettingKey(const std::string& key) {
  for (const char* prefix : {"fusion.", "planes.", "merge."}) {
    if (key.rfind(prefix, 0) == 0) return true;
  }
  return false;
}

}  // namespace

Status ApplyMapSettings(const MapSettings& settings, const ServerConfig& base, ServerConfig* out) {
  ServerConfig config = base;
  for (const auto& [key, value] : settings) {
    // One `key = value` line each in the file: nothing that could end a
    // line or start a comment there.
    for (const std::string* text : {&key, &value}) {
      for (const char c : *text) {
        if (static_cast<unsigned char>(c) < 0x20 || c == 0x7f || c == '#') {
          return Status::InvalidArgument("settings: '" + key.substr(0, 100) +
                                         "' has a control character or '#' in its key or value");
        }
      }
    }
    if (!IsMapSettingKey(key)) {
      return Status::InvalidArgument("settings: '" + key.substr(0, 100) +
                                     "' is not a map's setting: a map may set fusion.*, planes.* "
                                     "and merge.* keys (mapd --help lists them)");
    }
    if (Status s = ApplySetting(key, value, &config); !s.ok()) {
      return Status::InvalidArgument("settings: " + s.message());
    }
  }
  if (Status s = config.Validate(); !s.ok()) {
    return Status::InvalidArgument("settings: " + s.message());
  }
  *out = std::move(config);
  return Status::Ok();
}

std::string MapSettingsPath(const std::string& db_path) {
  return std::filesystem::path(db_path).replace_extension(".conf").string();
}

StatusOr<MapSettings> ReadMapSettings(const std::string& path) {
  MapSettings settings;
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) return settings;
  Status read = ForEachConfigLine(path, [&](const std::string& key, const std::string& value) {
    settings[key] = value;
    return Status::Ok();
  });
  if (read.code() == StatusCode::kNotFound)
    return Status::FailedPrecondition("cannot read the map's settings '" + path + "'");
  if (!read.ok()) return read;
  return settings;
}

std::string MapSettingsText(const MapSettings& settings) {
  std::string text = "# This map's own settings (mapctl maps create --set), over mapd's.\n";
  for (const auto& [key, value] : settings) text.append(key).append(" = ").append(value) += '\n';
  return text;
}

StatusOr<MapSettings> ParseMapSettings(const std::string& text, const std::string& name) {
  MapSettings settings;
  MAPD_RETURN_IF_ERROR(
      ForEachConfigTextLine(text, name, [&](const std::string& key, const std::string& value) {
        settings[key] = value;
        return Status::Ok();
      }));
  return settings;
}

Status WriteMapSettings(const std::string& path, const MapSettings& settings) {
  const std::string text = MapSettingsText(settings);
  const std::string tmp = path + ".tmp";
  const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0600);
  if (fd < 0)
    return Status::FailedPrecondition("cannot write '" + tmp + "': " + std::strerror(errno));
  const bool written = ::write(fd, text.data(), text.size()) == static_cast<ssize_t>(text.size()) &&
                       ::fsync(fd) == 0;
  ::close(fd);
  if (!written || std::rename(tmp.c_str(), path.c_str()) != 0) {
    std::remove(tmp.c_str());
    return Status::FailedPrecondition("cannot write the map's settings '" + path + "'");
  }
  return Status::Ok();
}

}  // namespace mapd::service
