#include "service/server.h"

#include <grpcpp/ext/proto_server_reflection_plugin.h>
#include <grpcpp/health_check_service_interface.h>
#include <malloc.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "common/clock.h"
#include "service/file_modes.h"
#include "service/log.h"
#include "service/rpc_metrics.h"

namespace mapd::service {
namespace {

StatusOr<std::string> ReadFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return Status::NotFound("cannot read '" + path + "'");
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

// "on" when glibc's malloc was started with transparent huge pages
// (GLIBC_TUNABLES glibc.malloc.hugetlb=1 or 2, read by glibc at process
// start only), else what to set: deploy/mapd.service and the container do.
std::string MallocHugePages() {
  const char* tunables = std::getenv("GLIBC_TUNABLES");
  const std::string value = tunables == nullptr ? "" : tunables;
  const std::string key = "glibc.malloc.hugetlb=";
  const std::size_t at = value.rfind(key);
  if (at != std::string::npos && (at == 0 || value[at - 1] == ':')) {
    const char mode = at + key.size() < value.size() ? value[at + key.size()] : '0';
    if (mode == '1' || mode == '2') return "on";
  }
  return "off (merges of large submaps take 20-45 % more CPU, in page faults; start mapd with "
         "GLIBC_TUNABLES=glibc.malloc.hugetlb=1, docs/operations.md)";
}

}  // namespace

StatusOr<std::unique_ptr<MapServer>> MapServer::Start(const ServerConfig& config) {
  MAPD_RETURN_IF_ERROR(config.Validate());
  std::unique_ptr<MapServer> server(new MapServer());
  server->config_ = config;
  if (server->config_.db_path.empty() && config.data_dir.empty() && config.store.empty())
    server->config_.db_path = DefaultDbPath();
  const std::string& db = server->config_.db_path;
  std::error_code ec;
  const auto parent = std::filesystem::path(db).parent_path();
  if (!config.data_dir.empty() || !config.store.empty()) {
    // The maps' directory is the operator's: MapDirectory checks it exists.
  } else if (config.db_path.empty()) {
    // The default path's directory is mapd's own: made on first use.
    // Only the last directory is mapd's own, made owner-only (the rest,
    // e.g. ~/.local/share, belongs to the user's session).
    if (!parent.empty() && std::filesystem::create_directories(parent, ec) && !ec) {
      std::filesystem::permissions(parent, std::filesystem::perms::owner_all,
                                   std::filesystem::perm_options::replace, ec);
    }
    if (ec) {
      return Status::FailedPrecondition("cannot create the directory of the database '" + db +
                                        "': " + ec.message());
    }
  } else if (!parent.empty() && !std::filesystem::is_directory(parent, ec)) {
    // A typo in --db must not create a tree of directories and a new, empty map.
    return Status::FailedPrecondition("--db '" + db + "': the directory '" + parent.string() +
                                      "' does not exist; create it first (mkdir -p)");
  }
  AuthOptions& auth = server->auth_;  // docs/security.md
  auth.required = config.auth_required;
  auth.client_certs = !config.tls_client_ca.empty();
  auth.denials_per_minute = config.streams.audit_denials_per_minute;
  auth.denials = std::make_shared<DenialAuditLimiter>(auth.denials_per_minute);
  MapServer* s = server.get();
  MapDirectory::Opener opener = [s](const std::string& id, const std::string& path,
                                    MapServiceImpl* shared_with, const MapSettings* create_with) {
    return s->OpenMap(id, path, shared_with, create_with);
  };
  StatusOr<std::unique_ptr<MapDirectory>> maps = Status::Internal("no maps");
  if (!config.store.empty()) {
    MAPD_RETURN_IF_ERROR(storage::CheckConninfo(config.store));
    StatusOr<storage::PgMapCatalog> catalog = storage::PgMapCatalog::Open(config.store);
    if (!catalog.ok()) {
      return Status(catalog.status().code(), "store: " + catalog.status().message());
    }
    server->catalog_ = std::make_unique<storage::PgMapCatalog>(std::move(catalog).value());
    StatusOr<ServerWide> server_wide = server->OpenServerWide();
    if (!server_wide.ok()) return server_wide.status();
    maps = MapDirectory::ForPostgres(std::move(server_wide).value(), opener);
  } else if (!config.data_dir.empty()) {
    maps = MapDirectory::OpenDataDir(config.data_dir, opener);
  } else {
    maps = MapDirectory::OpenSingle(db, opener);
  }
  if (!maps.ok()) return maps.status();
  server->maps_ = std::move(maps).value();
  if (!config.store.empty()) {
    MapOwnership::Hooks hooks;
    hooks.open = [s](const std::string& id) { return s->TakeMap(id); };
    hooks.drop = [s](const std::string& id, const Status& why) { s->DropMap(id, why); };
    hooks.hand_off = [s](const std::string& id) { return s->HandOffMap(id); };
    OwnershipOptions o;
    o.conninfo = config.store;
    o.lease_ttl_s = config.lease_ttl_s;
    StatusOr<std::unique_ptr<MapOwnership>> ownership =
        MapOwnership::Create(o, server->maps_.get(), server->catalog_.get(), std::move(hooks));
    if (!ownership.ok()) return ownership.status();
    server->ownership_ = std::move(ownership).value();
  }
  if (!config.store.empty() && config.forward && config.tls_client_ca.empty()) {
    std::shared_ptr<grpc::ChannelCredentials> to_peers;
    if (config.tls_cert.empty()) {
      to_peers = grpc::InsecureChannelCredentials();
    } else if (!config.forward_ca.empty()) {
      StatusOr<std::string> ca = ReadFile(config.forward_ca);
      if (!ca.ok()) return Status::InvalidArgument("forward_ca: " + ca.status().message());
      grpc::SslCredentialsOptions ssl;
      ssl.pem_root_certs = *ca;
      to_peers = grpc::SslCredentials(ssl);
    }
    if (to_peers != nullptr) {
      server->forwarder_ = std::make_unique<MapForwarder>(
          to_peers, config.instance_name, static_cast<int>(config.max_message_bytes));
    }
  }
  server->router_ = std::make_unique<MapRouter>(server->maps_.get(), s, server->ownership_.get(),
                                                server->forwarder_.get());
  SetLogRateLimit(config.streams.log_lines_per_s);

  std::shared_ptr<grpc::ServerCredentials> credentials = grpc::InsecureServerCredentials();
  if (!config.tls_cert.empty()) {
    StatusOr<std::string> cert = ReadFile(config.tls_cert);
    if (!cert.ok()) return Status::InvalidArgument("tls_cert: " + cert.status().message());
    MAPD_RETURN_IF_ERROR(CheckSecretFileMode(config.tls_key, "tls_key"));
    StatusOr<std::string> key = ReadFile(config.tls_key);
    if (!key.ok()) return Status::InvalidArgument("tls_key: " + key.status().message());
    grpc::SslServerCredentialsOptions ssl;
    ssl.pem_key_cert_pairs.push_back({*key, *cert});
    if (!config.tls_client_ca.empty()) {  // mTLS: a client certificate's CN is a robot id
      StatusOr<std::string> ca = ReadFile(config.tls_client_ca);
      if (!ca.ok()) return Status::InvalidArgument("tls_client_ca: " + ca.status().message());
      ssl.pem_root_certs = *ca;
      ssl.client_certificate_request = GRPC_SSL_REQUEST_AND_REQUIRE_CLIENT_CERTIFICATE_AND_VERIFY;
    }
    credentials = grpc::SslServerCredentials(ssl);
  }

  grpc::EnableDefaultHealthCheckService(true);
  grpc::reflection::InitProtoReflectionServerBuilderPlugin();
  grpc::ServerBuilder builder;
  builder.AddListeningPort(config.listen, credentials, &server->port_);
  if (!config.health_listen.empty()) {  // plaintext, loopback only (config.cc)
    builder.AddListeningPort(config.health_listen, grpc::InsecureServerCredentials(),
                             &server->health_port_);
  }
  builder.RegisterService(server->router_.get());
  // Every call counted by method and code, and timed (rpc_metrics.h, /metrics).
  std::vector<std::unique_ptr<grpc::experimental::ServerInterceptorFactoryInterface>> interceptors;
  interceptors.push_back(RpcMetrics::InterceptorFactory());
  interceptors.push_back(server->calls_.InterceptorFactory());
  builder.experimental().SetInterceptorCreators(std::move(interceptors));
  builder.SetMaxReceiveMessageSize(static_cast<int>(config.max_message_bytes));
  builder.SetMaxSendMessageSize(static_cast<int>(config.max_message_bytes));
  // gRPC sets SO_REUSEPORT by default: a second mapd on the same port would
  // silently share it. One server per port.
  builder.AddChannelArgument(GRPC_ARG_ALLOW_REUSEPORT, 0);
  // Connection and stream limits (config.h, StreamLimits): the HTTP/2 stream
  // cap per connection, keepalive (dead peers are dropped), ping-flood
  // protection, idle and maximal connection age.
  const StreamLimits& limits = config.streams;
  auto ms = [](double seconds) { return static_cast<int>(std::min(seconds * 1000.0, 2.0e9)); };
  builder.AddChannelArgument(GRPC_ARG_MAX_CONCURRENT_STREAMS,
                             static_cast<int>(limits.max_streams_per_connection));
  builder.AddChannelArgument(GRPC_ARG_KEEPALIVE_TIME_MS, ms(limits.keepalive_time_s));
  builder.AddChannelArgument(GRPC_ARG_KEEPALIVE_TIMEOUT_MS, ms(limits.keepalive_timeout_s));
  builder.AddChannelArgument(GRPC_ARG_KEEPALIVE_PERMIT_WITHOUT_CALLS, 1);
  builder.AddChannelArgument(GRPC_ARG_HTTP2_MIN_RECV_PING_INTERVAL_WITHOUT_DATA_MS,
                             ms(limits.min_client_ping_interval_s));
  builder.AddChannelArgument(GRPC_ARG_HTTP2_MAX_PING_STRIKES, 2);
  if (limits.max_connection_idle_s > 0) {
    builder.AddChannelArgument(GRPC_ARG_MAX_CONNECTION_IDLE_MS, ms(limits.max_connection_idle_s));
  }
  if (limits.max_connection_age_s > 0) {
    builder.AddChannelArgument(GRPC_ARG_MAX_CONNECTION_AGE_MS, ms(limits.max_connection_age_s));
    builder.AddChannelArgument(GRPC_ARG_MAX_CONNECTION_AGE_GRACE_MS, ms(config.shutdown_grace_s));
  }
  server->server_ = builder.BuildAndStart();
  if (!server->server_ || server->port_ == 0 ||
      (!config.health_listen.empty() && server->health_port_ == 0)) {
    const std::string& where = server->port_ == 0 ? config.listen : config.health_listen;
    return Status::Unavailable("cannot listen on '" + where +
                               "' (address in use, or not an address of this host?)");
  }
  if (server->health_port_ != 0) {
    const std::string& h = config.health_listen;
    Log(LogLevel::kInfo, "health_listening",
        {{"address", h.substr(0, h.rfind(':')) + ":" + std::to_string(server->health_port_)}});
  }
  server->server_->GetHealthCheckService()->SetServingStatus(false);
  Log(LogLevel::kInfo, "listening",
      {{"address", server->address()},
       {!config.store.empty()     ? "store"
        : config.data_dir.empty() ? "db"
                                  : "data_dir",
        !config.store.empty()     ? "postgresql"
        : config.data_dir.empty() ? db
                                  : config.data_dir},
       {"maps", std::to_string(server->maps_->List().size())},
       {"health", "NOT_SERVING"},
       {"reason", "recovering the fused map"},
       {"malloc_huge_pages", MallocHugePages()}});
  for (const MapHold& map : server->maps_->List()) server->WatchMap(map.get());
  server->router_->set_address(server->Instance().address);
  if (server->ownership_ != nullptr) {
    // Who this instance is, now that the port is bound (port 0 in tests).
    server->ownership_->set_instance(server->Instance());
    // The first round before returning: a lone instance serves its maps at once.
    if (Status round = server->ownership_->RunOnce(); !round.ok()) return round;
    server->ownership_->StartThread();
    {
      std::lock_guard<std::mutex> lock(server->health_mu_);
      server->UpdateHealthLocked();  // "" is SERVING with no map here
    }
  }
  server->housekeeping_ = std::thread([s] { s->Housekeeping(); });
  return server;
}

StatusOr<std::unique_ptr<ServedMap>> MapServer::OpenMap(const std::string& id,
                                                        const std::string& db_path,
                                                        MapServiceImpl* shared_with,
                                                        const MapSettings* create_with) {
  auto map = std::make_unique<ServedMap>();
  map->id = id;
  map->db_path = db_path;
  if (catalog_ != nullptr) return OpenPostgresMap(std::move(map), shared_with, create_with);
  // A map's own settings (map_settings.h): only maps of a data directory
  // have them, in <id>.conf; a new one's are checked and stored first.
  ServerConfig config = config_;
  const std::string settings_path = MapSettingsPath(db_path);
  bool wrote_settings = false;
  if (create_with != nullptr && !create_with->empty()) {
    MAPD_RETURN_IF_ERROR(ApplyMapSettings(*create_with, config_, &config));
    MAPD_RETURN_IF_ERROR(WriteMapSettings(settings_path, *create_with));
    wrote_settings = true;
  }
  auto fail = [&](const Status& s) {
    // A map that could not be made leaves no file behind (the lock creates
    // the database file), so that the same id can be tried again.
    if (wrote_settings) std::remove(settings_path.c_str());
    if (create_with != nullptr) {
      map->lock = DatabaseLock();
      for (const char* suffix : {"", "-wal", "-shm"}) std::remove((db_path + suffix).c_str());
    }
    return id == kDefaultMapId ? s : Status(s.code(), "map '" + id + "': " + s.message());
  };
  if (!config_.data_dir.empty()) {
    StatusOr<MapSettings> settings = ReadMapSettings(settings_path);
    if (!settings.ok()) return fail(settings.status());
    if (Status s = ApplyMapSettings(*settings, config_, &config); !s.ok()) {
      return fail(Status(s.code(), settings_path + ": " + s.message()));
    }
    map->settings = *std::move(settings);
  }
  StatusOr<DatabaseLock> lock = DatabaseLock::Acquire(db_path);
  if (!lock.ok()) return fail(lock.status());
  map->lock = std::move(lock).value();
  MapCoreOptions core_options = CoreOptions(config);
  core_options.db_path = db_path;
  StatusOr<std::unique_ptr<MapCore>> core = MapCore::Open(core_options);
  if (!core.ok()) return fail(core.status());
  map->core = std::move(core).value();
  map->service =
      std::make_unique<MapServiceImpl>(map->core.get(), config.ingest, config.submaps,
                                       config.streams, auth_, MapPlacement{id, shared_with});
  return map;
}

MapCoreOptions MapServer::CoreOptions(const ServerConfig& config) {
  MapCoreOptions core_options;
  core_options.store.synchronous_full = config.sync_full;
  core_options.store.busy_timeout_ms = config.busy_timeout_ms;
  core_options.store.max_db_bytes = config.max_db_bytes;
  core_options.stop_flush_s = config.shutdown_flush_s;
  core_options.fusion = config.fusion;
  core_options.planes = config.planes;
  core_options.max_group_batches = config.max_group_batches;
  core_options.fusion_share.after_s = config.fusion_share_after_s;
  core_options.fusion_share.factor = config.fusion_share_factor;
  core_options.snapshot_every_observations = config.snapshot_every_observations;
  core_options.snapshot_max_age_s = config.snapshot_max_age_s;
  core_options.raw_retention_days = config.raw_retention_days;
  core_options.watch = config.watch;
  core_options.hold_fuser_for_test = config.hold_fuser_for_test;
  return core_options;
}

void MapServer::WatchMap(ServedMap* map) {
  const std::string id = map->id, db = map->db_path;
  map->core->write_health().SetListener([this, id](const Status& failure) {
    std::lock_guard<std::mutex> lock(health_mu_);
    if (failure.ok()) {
      Log(LogLevel::kInfo, "writable_again", {{"map", id}, {"health", "SERVING"}});
    } else {
      Log(LogLevel::kError, "not_writable",
          {{"map", id},
           {"health", "NOT_SERVING"},
           {"reason", failure.message()},
           {"action",
            "batches and uploads are refused (robots resend); free disk space or fix the database "
            "file; mapd probes every second and serves again by itself"}});
    }
    UpdateHealthLocked();
  });
  map->core->OnReady([this, id, db, sync = config_.sync_full, fusion = config_.fusion] {
    std::lock_guard<std::mutex> lock(health_mu_);
    if (shut_down_) return;
    UpdateHealthLocked();
    Log(LogLevel::kInfo, "serving",
        {{"address", address()},
         {"map", id},
         {"db", db},
         {"sync", sync ? "full" : "normal"},
         {"fusion_mode", fusion::FusionModeName(fusion.mode)},
         {"corner_mode", fusion::CornerModeName(fusion.corner_mode)}});
  });
}

void MapServer::UpdateHealthLocked() {
  grpc::HealthCheckServiceInterface* health = server_->GetHealthCheckService();
  bool all = !shut_down_;
  for (const MapHold& map : maps_->List()) {
    const bool serving = !shut_down_ && map->core->ready() && map->core->write_health().ok();
    health->SetServingStatus("map/" + map->id, serving);
    all = all && serving;
  }
  health->SetServingStatus(all);
}

void MapServer::Housekeeping() {
  uint64_t last_events = 0, since_trim = 0;
  int seconds_since_trim = 0;
  std::unique_lock<std::mutex> lock(housekeeping_mu_);
  while (!housekeeping_cv_.wait_for(lock, std::chrono::seconds(1),
                                    [this] { return housekeeping_stop_; })) {
    lock.unlock();
    if (maps_->postgres()) maps_->server_wide().Tick();  // its audit rows and denials
    for (const MapHold& map : maps_->List()) map->service->Tick();
    maps_->Reap();  // deleted, handed-off and dropped maps, once no call holds them
    FlushSuppressedLogs();
    // Give memory back after a burst: a flood of streams leaves gRPC's and
    // malloc's freed memory in the heap (1.5 GiB, never returned, before).
    // Trim once the burst is over (under 100 stream opens in the last
    // second), and every 30 s anyway.
    const StreamLimiter& limiter = maps_->server_wide().limiter();  // shared by all
    const uint64_t events = limiter.admitted() + limiter.refused();
    const uint64_t last_second = events - last_events;
    last_events = events;
    since_trim += last_second;
    if ((since_trim > 1000 && last_second < 100) || ++seconds_since_trim >= 30) {
      malloc_trim(0);
      since_trim = 0;
      seconds_since_trim = 0;
    }
    lock.lock();
  }
}

bool MapServer::WaitUntilServing(std::chrono::duration<double> timeout) const {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  for (const MapHold& map : maps_->List()) {
    const MapCore& core = *map->core;
    if (!core.WaitUntilReady(deadline - std::chrono::steady_clock::now()) ||
        !core.CheckReady().ok()) {
      return false;
    }
  }
  return true;
}

std::string MapServer::address() const {
  const std::string& l = config_.listen;
  return l.substr(0, l.rfind(':')) + ":" + std::to_string(port_);
}

void MapServer::Shutdown() {
  {
    std::lock_guard<std::mutex> lock(health_mu_);
    if (shut_down_ || !server_) return;  // never started: nothing to drain
    shut_down_ = true;
  }
  Log(LogLevel::kInfo, "shutting_down", {{"grace_s", std::to_string(config_.shutdown_grace_s)}});
  if (ownership_ != nullptr) ownership_->StopTaking();  // leases still renewed while draining
  {
    std::lock_guard<std::mutex> lock(health_mu_);
    UpdateHealthLocked();  // NOT_SERVING, every map
  }
  for (const MapHold& map : maps_->List()) map->service->StartDraining();
  // The calls in progress get the grace period; then gRPC gets 100 ms more
  // (for a call that came in just now) before it cancels what is left and
  // closes the idle connections, which it would otherwise wait for
  // (calls_in_progress.h).
  const auto grace =
      std::chrono::milliseconds(static_cast<int64_t>(config_.shutdown_grace_s * 1000));
  const auto start = std::chrono::steady_clock::now();
  const bool calls_ended = calls_.WaitUntilNone(start + grace);
  const auto left = grace - std::chrono::duration_cast<std::chrono::milliseconds>(
                                std::chrono::steady_clock::now() - start);
  const auto linger =
      std::clamp(left, std::chrono::milliseconds(0), std::chrono::milliseconds(100));
  if (!calls_ended) {
    Log(LogLevel::kWarn, "shutdown_grace_over",
        {{"calls_cancelled", std::to_string(calls_.count())},
         {"grace_s", std::to_string(config_.shutdown_grace_s)}});
  }
  server_->Shutdown(std::chrono::system_clock::now() + linger);  // returns once every RPC has ended
  StopHousekeeping();
  // The counts of the last denials (denial_audit.h), into the default map's
  // database, before it stops.
  maps_->server_wide().FlushDenials(/*all=*/true);
  for (const MapHold& map : maps_->List())
    map->core->Stop();  // commits what is queued, checkpoints
  // The leases lapse as the stores close (MapServer's destructor), so that
  // the maps' next owners take them at once.
  if (ownership_ != nullptr) ownership_->Stop();
  Log(LogLevel::kInfo, "stopped");
}

void MapServer::Wait() {
  if (server_) server_->Wait();
}

void MapServer::StopHousekeeping() {
  {
    std::lock_guard<std::mutex> lock(housekeeping_mu_);
    housekeeping_stop_ = true;
  }
  housekeeping_cv_.notify_all();
  if (housekeeping_.joinable()) housekeeping_.join();
}

MapServer::~MapServer() {
  Shutdown();
  StopHousekeeping();
}

}  // namespace mapd::service
