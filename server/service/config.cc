#include "service/config.h"

#include <cstdlib>
#include <fstream>
#include <sstream>

#include "service/config_settings.h"
#include "service/loopback.h"

namespace mapd::service {
namespace {

std::string Trim(const std::string& s) {
  const size_t b = s.find_first_not_of(" \t\r");
  if (b == std::string::npos) return "";
  const size_t e = s.find_last_not_of(" \t\r");
  return s.substr(b, e - b + 1);
}

const Setting* Find(const std::string& key) {
  for (const Setting& s : Settings()) {
    if (s.key == key) return &s;
  }
  return nullptr;
}

// "fusion" for "fusion.gamma", "" for "listen": the example file's sections.
std::string Section(const std::string& key) {
  const size_t dot = key.find('.');
  return dot == std::string::npos ? "" : key.substr(0, dot);
}

// InvalidArgument naming `key` unless `value` is host:port with a port in 0..65535.
Status CheckHostPort(const char* key, const std::string& value) {
  if (value.empty() || value.find(':') == std::string::npos) {
    return Status::InvalidArgument(std::string(key) + ": '" + value + "' is not host:port");
  }
  // gRPC would take the port modulo 65536 (99999 listened on 34463).
  const std::string port = value.substr(value.rfind(':') + 1);
  const bool digits = !port.empty() && port.size() <= 5 &&
                      port.find_first_not_of("0123456789") == std::string::npos;
  if (!digits || std::stoul(port) > 65535) {
    return Status::InvalidArgument(std::string(key) + ": '" + value + "': the port '" + port +
                                   "' is not a number in 0..65535");
  }
  return Status::Ok();
}

}  // namespace

std::string DefaultDbPath() {
  if (const char* d = std::getenv("MAPD_DATA_DIR"); d && *d) return std::string(d) + "/map.db";
  if (const char* x = std::getenv("XDG_DATA_HOME"); x && *x) return std::string(x) + "/mapd/map.db";
  const char* home = std::getenv("HOME");
  return std::string(home && *home ? home : ".") + "/.local/share/mapd/map.db";
}

bool ListenIsLoopback(const std::string& listen) {
  if (listen.rfind("unix:", 0) == 0) return true;
  const size_t colon = listen.rfind(':');
  if (colon == std::string::npos) return false;
  std::string host = listen.substr(0, colon);
  if (host.size() >= 2 && host.front() == '[' && host.back() == ']')
    host = host.substr(1, host.size() - 2);
  if (host.empty()) return false;  // ":50051" listens on every interface
  // The addresses the name stands for, not its text: a host name that
  // resolves to 0.0.0.0 (or to a public address) is not loopback.
  return IsLoopbackAddress(host);
}

Status ServerConfig::Validate() const {
  for (const Setting& s : Settings()) MAPD_RETURN_IF_ERROR(s.check(*this));
  // The algorithm libraries check their own structs too (they are used
  // without mapd); their messages name the field.
  Status f = fusion.Validate();
  if (!f.ok()) return Status::InvalidArgument("fusion: " + f.message());
  Status pl = planes.Validate();
  if (!pl.ok()) return Status::InvalidArgument("planes: " + pl.message());
  Status l = ingest.limits.Validate();
  if (!l.ok()) return Status::InvalidArgument("limits: " + l.message());
  if (ingest.limits.max_feature_length_m > fusion.max_wall_length_m) {
    // Else a batch would be acknowledged that the fuser then refuses.
    return Status::InvalidArgument(
        "limits.max_feature_length_m must be at most fusion.max_wall_length_m");
  }
  if (!db_path.empty() && !data_dir.empty()) {
    return Status::InvalidArgument(
        "db and data_dir are both set: db serves one map from one file, data_dir several maps "
        "from one directory; set one");
  }
  if (!store.empty()) {
    if (!db_path.empty() || !data_dir.empty()) {
      return Status::InvalidArgument(
          "store is set with " + std::string(db_path.empty() ? "data_dir" : "db") +
          ": store serves the maps of a PostgreSQL database, db and data_dir SQLite files; set "
          "one");
    }
  }
  MAPD_RETURN_IF_ERROR(CheckHostPort("listen", listen));
  if (!health_listen.empty()) MAPD_RETURN_IF_ERROR(CheckHostPort("health_listen", health_listen));
  if (tls_cert.empty() != tls_key.empty()) {
    return Status::InvalidArgument("tls_cert and tls_key must be given together");
  }
  if (tls_cert.empty() && !allow_insecure_remote && !ListenIsLoopback(listen)) {
    return Status::InvalidArgument(
        "listen: '" + listen +
        "' is not (or does not resolve only to) a loopback address; give tls_cert "
        "and tls_key, or allow_insecure_remote=true on a trusted network");
  }
  if (!tls_client_ca.empty() && tls_cert.empty()) {
    return Status::InvalidArgument(
        "tls_client_ca needs tls_cert and tls_key (client certificates need TLS)");
  }
  if (!auth_required && tls_client_ca.empty() && !ListenIsLoopback(listen)) {
    return Status::InvalidArgument(
        "listen: '" + listen +
        "' is not loopback; set auth.required = true (create tokens with "
        "`mapd token create`) or tls_client_ca");
  }
  if (!health_listen.empty() && !ListenIsLoopback(health_listen)) {
    return Status::InvalidArgument("health_listen: '" + health_listen +
                                   "' is not a loopback host:port; it is plaintext, for a local "
                                   "health probe (e.g. 127.0.0.1:50052)");
  }
  // Plain HTTP: off loopback tokens and the map would cross the network in the clear.
  if (web.port != 0 && !allow_insecure_remote &&
      !ListenIsLoopback(web.address + ":" + std::to_string(web.port))) {
    return Status::InvalidArgument("http.address: '" + web.address +
                                   "' is not loopback; the web view is plain HTTP: put a TLS "
                                   "proxy in front, or allow_insecure_remote=true on a trusted "
                                   "network");
  }
  return Status::Ok();
}

Status ApplySetting(const std::string& key, const std::string& value, ServerConfig* config) {
  const Setting* s = Find(key);
  if (s == nullptr)
    return Status::InvalidArgument("unknown setting '" + key + "' (see mapd --help)");
  return s->set(value, config);
}

Status ForEachConfigLine(
    const std::string& path,
    const std::function<Status(const std::string& key, const std::string& value)>& fn) {
  std::ifstream in(path);
  if (!in) return Status::NotFound("cannot read config file '" + path + "'");
  std::stringstream text;
  text << in.rdbuf();
  return ForEachConfigTextLine(text.str(), path, fn);
}

Status ForEachConfigTextLine(
    const std::string& text, const std::string& path,
    const std::function<Status(const std::string& key, const std::string& value)>& fn) {
  std::istringstream in(text);
  std::string line;
  for (int n = 1; std::getline(in, line); ++n) {
    line = Trim(line.substr(0, line.find('#')));
    if (line.empty()) continue;
    const size_t eq = line.find('=');
    if (eq == std::string::npos) {
      return Status::InvalidArgument(path + ":" + std::to_string(n) + ": expected key = value");
    }
    Status s = fn(Trim(line.substr(0, eq)), Trim(line.substr(eq + 1)));
    if (!s.ok())
      return Status::InvalidArgument(path + ":" + std::to_string(n) + ": " + s.message());
  }
  return Status::Ok();
}

Status LoadConfigFile(const std::string& path, ServerConfig* config) {
  return ForEachConfigLine(path, [config](const std::string& key, const std::string& value) {
    return ApplySetting(key, value, config);
  });
}

std::string ConfigFileText(const ServerConfig& config) {
  std::ostringstream out;
  out << "# mapd configuration: `key = value`; every key is also a flag (--key value).\n"
         "# Written by `mapd --print-config`; `mapd --help` explains each setting.\n";
  std::string section = "-";
  for (const Setting& s : Settings()) {
    if (Section(s.key) != section) {
      section = Section(s.key);
      out << "\n";
    }
    out << "# " << s.help << "\n";
    const std::string value = s.get(config);
    out << (value.empty() ? "# " + s.key + " =" : s.key + " = " + value) << "\n";
  }
  return out.str();
}

}  // namespace mapd::service
