// mapd's configuration: one struct, filled from defaults, then a config file,
// then command-line flags. The file holds `key = value` lines (# comments);
// every key is also a flag: `--fusion.gamma=0.4` or `--fusion.gamma 0.4`
// (parsed in server/mapd/command_line.h).
// The defaults are the member initialisers below and nowhere else: the
// settings table (config_settings.cc) reads them for --help and the example
// file.
#ifndef MAPD_SERVICE_CONFIG_H_
#define MAPD_SERVICE_CONFIG_H_

#include <functional>
#include <string>
#include <vector>

#include "common/status.h"
#include "fusion/params.h"
#include "fusion/plane_engine.h"
#include "service/options.h"

namespace mapd::service {

struct ServerConfig {
  std::string listen = "127.0.0.1:50051";  // host:port; port 0 picks a free one
  std::string db_path;                     // empty: DefaultDbPath()
  // Several maps, one SQLite file <map id>.db each (map_directory.h); not
  // with db_path. Empty: one map in db_path.
  std::string data_dir;
  // Every map in one PostgreSQL database (libpq key=value string or
  // postgresql:// URI, no password); not with db_path or data_dir.
  std::string store;
  // With store: who this instance is among the mapd serving that database
  // (map_ownership.h). advertise_address: where clients reach it (host:port;
  // empty: the listen address, its host replaced by this host's name when it
  // listens on every interface). instance_name: stays the same across
  // restarts (empty: the advertised address). lease_ttl_s: how long a map
  // stays with an instance that stopped renewing, seconds.
  std::string advertise_address;
  std::string instance_name;
  double lease_ttl_s = 3.0;
  // With store: relay calls for a map another instance serves to it
  // (map_forwarder.h); with tls_cert only if forward_ca names the CA of the
  // instances' certificates, and never with tls_client_ca. Off: redirects.
  bool forward = true;
  std::string forward_ca;
  bool sync_full = false;      // synchronous=FULL (survives power loss)
  int busy_timeout_ms = 5000;  // wait for a database lock held by another process
  fusion::FusionParams fusion;
  fusion::PlaneFusionParams planes;  // non-vertical planes (floors, ramps)
  IngestOptions ingest;
  SubmapOptions submaps;
  StreamLimits streams;
  WatchOptions watch;  // WatchFeatureMap: history, per-watcher queue, watchers at once
  WebOptions web;      // the web view's HTTP port (off by default)
  size_t max_message_bytes = 16u << 20;  // largest gRPC message accepted
  size_t max_group_batches = 4096;       // batches per group commit at most
  // A robot keeping the fuser busy (service/fusion_share.h): shares are
  // enforced once this much fusion work waits, seconds (0: never), and a
  // robot may keep this many times the other robots' average waiting.
  double fusion_share_after_s = 1.0;
  double fusion_share_factor = 4.0;
  uint64_t snapshot_every_observations = 20000;  // fusion snapshot cadence (0: never)
  double snapshot_max_age_s = 60.0;              // ... or once the newest is this old
  double raw_retention_days = 0.0;               // 0: keep raw observations forever
  double shutdown_grace_s = 5.0;                 // SIGTERM: time given to streams to finish
  double shutdown_flush_s = 5.0;  // ... then to commit what is queued if the disk fails
  uint64_t max_db_bytes = 0;      // database size cap (as a full disk beyond), 0: none
  std::string tls_cert;           // PEM files; required off loopback
  std::string tls_key;
  bool allow_insecure_remote = false;  // serve plaintext off loopback anyway
  // Identities (docs/security.md): every call needs a credential even with no
  // token in the database yet. Required off loopback (or tls_client_ca).
  bool auth_required = false;
  std::string tls_client_ca;  // PEM CA: clients must present a certificate it signed
  // A second, plaintext port on loopback, for health checks that carry no
  // client certificate under mTLS; empty = none. Every other RPC on it
  // follows the usual rules (with tls_client_ca: a token, no open mode).
  std::string health_listen;
  std::string log_level = "info";  // debug, info, warn, error
  // Tests only, never set by a flag or a file: MapCoreOptions::hold_fuser_for_test.
  // mapd sets it from $MAPD_TEST_HOLD_FUSER_FILE (server/mapd/main.cc).
  std::function<bool()> hold_fuser_for_test;

  // Every setting's range (the table), the libraries' own checks, and the
  // rules between settings (TLS off loopback).
  Status Validate() const;
};

// $MAPD_DATA_DIR/map.db, else $XDG_DATA_HOME/mapd/map.db, else ~/.local/share/mapd/map.db.
std::string DefaultDbPath();

// Sets one key (see the table in config.cc); InvalidArgument names the key.
Status ApplySetting(const std::string& key, const std::string& value, ServerConfig* config);
Status LoadConfigFile(const std::string& path, ServerConfig* config);
// Calls `fn` with each `key = value` line of the config file `path` (blank
// lines and # comments skipped, both sides trimmed). NotFound when it cannot be
// read; InvalidArgument "path:line: ..." for a line without '=' or fn's error.
Status ForEachConfigLine(
    const std::string& path,
    const std::function<Status(const std::string& key, const std::string& value)>& fn);
// The same for `text` held elsewhere (a map's settings in PostgreSQL);
// messages say "name:line".
Status ForEachConfigTextLine(
    const std::string& text, const std::string& name,
    const std::function<Status(const std::string& key, const std::string& value)>& fn);

// `config` as a config file: every setting with its help line, in table order.
// ConfigFileText(ServerConfig()) is deploy/mapd.conf.example.
std::string ConfigFileText(const ServerConfig& config);
// True when every address `listen`'s host resolves to is a loopback address
// (127.0.0.0/8, ::1) or it is a unix: socket.
bool ListenIsLoopback(const std::string& listen);

}  // namespace mapd::service

#endif  // MAPD_SERVICE_CONFIG_H_
