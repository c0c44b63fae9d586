// MapServer: the maps (map_directory.h: each a MapCore and its handlers) and
// the gRPC server around them (routing, health, reflection, TLS).
#ifndef MAPD_SERVICE_SERVER_H_
#define MAPD_SERVICE_SERVER_H_

#include <grpcpp/grpcpp.h>

#include <chrono>
#include <condition_variable>
#include <memory>
#include <mutex>
#include <string>
#include <thread>

#include "common/status.h"
#include "service/access_control.h"
#include "service/calls_in_progress.h"
#include "service/config.h"
#include "service/map_core.h"
#include "service/map_directory.h"
#include "service/map_lifecycle.h"
#include "service/map_ownership.h"
#include "service/map_router.h"
#include "service/map_service.h"
#include "storage/postgres/map_catalog.h"

namespace mapd::service {

class MapServer final : public MapLifecycle {
 public:
  // Opens the database (or the maps of data_dir) and starts listening at
  // once. Each fused map is recovered in the background (MapCore::Open):
  // until then its health (service name "map/<id>") says NOT_SERVING and its
  // map RPCs answer UNAVAILABLE; then SERVING and an `event=serving` log
  // line. The server's health ("") is SERVING while every map is.
  static StatusOr<std::unique_ptr<MapServer>> Start(const ServerConfig& config);
  // Waits until every map is recovered; false on timeout or failed recovery.
  bool WaitUntilServing(std::chrono::duration<double> timeout) const;
  ~MapServer() override;

  // The port actually bound (useful with port 0).
  int port() const { return port_; }
  // The port of health_listen (0 when it is not set).
  int health_port() const { return health_port_; }
  std::string address() const;
  // The default map's core, for what runs beside the gRPC server (the web
  // view); on PostgreSQL the server-wide one while another instance serves it.
  Core* core() const {
    ServedMap* d = maps_->default_map();
    return d != nullptr ? d->core.get() : &maps_->server_wide_core();
  }
  MapDirectory& maps() const { return *maps_; }
  // Who may call, for what runs beside it (the web view): the same rules
  // and the same per-identity limit on denial rows in the audit log.
  const AuthOptions& auth() const { return auth_; }

  // Graceful stop: new batches are refused, streams end once their batches
  // in flight are acknowledged, calls in progress get shutdown_grace_s to
  // finish (idle client connections are not waited for), everything
  // accepted is committed, the WAL is checkpointed.
  void Shutdown();
  // Blocks until the gRPC server has shut down.
  void Wait();

  // MapLifecycle (server_maps.cc).
  void Created(ServedMap* map) override { WatchMap(map); }
  StatusOr<std::string> DeleteMap(const std::string& id, bool purge) override;
  StatusOr<MapHold> RestoreMap(const std::string& id) override;
  StatusOr<std::vector<ArchivedMap>> ListArchived() override;

 private:
  MapServer() = default;
  // Opens map `id` (MapDirectory::Opener).
  StatusOr<std::unique_ptr<ServedMap>> OpenMap(const std::string& id, const std::string& db_path,
                                               MapServiceImpl* shared_with,
                                               const MapSettings* create_with);
  // OpenMap for a map of the PostgreSQL database (config_.store).
  StatusOr<std::unique_ptr<ServedMap>> OpenPostgresMap(std::unique_ptr<ServedMap> map,
                                                       MapServiceImpl* shared_with,
                                                       const MapSettings* create_with);
  // PostgreSQL: the server-wide parts (server_wide_core.h).
  StatusOr<ServerWide> OpenServerWide();
  // PostgreSQL: this instance's name and advertised address (config_).
  storage::PgInstance Instance() const;
  // MapOwnership's hooks: serve map `id` here (its lease taken); stop
  // serving it (its lease lost), redirecting its calls from then on.
  Status TakeMap(const std::string& id);
  void DropMap(const std::string& id, const Status& why);
  // MapOwnership's hook: stop serving map `id` and release its lease.
  Status HandOffMap(const std::string& id);
  // What a map's MapCore takes from the (map's) configuration.
  static MapCoreOptions CoreOptions(const ServerConfig& config);
  // Logs and health for a map once it is in the directory.
  void WatchMap(ServedMap* map);
  // Each map SERVING once it is recovered, while its database takes writes
  // and until Shutdown(); "" while every map is. REQUIRES: health_mu_ held.
  void UpdateHealthLocked();
  // DeleteMap's parts: stop map `id` and archive it; delete an archive.
  StatusOr<std::string> Archive(const std::string& id, MapHold map);
  Status Purge(const std::string& id);
  bool IsArchived(const std::string& id);
  void Housekeeping();  // every second: idle uploads, log summaries, freed maps, memory trim
  void StopHousekeeping();

  ServerConfig config_;
  AuthOptions auth_;
  // With config_.store: the database's maps and their settings. Opening
  // maps is serialised by MapDirectory (at start, then one Create at a time).
  std::unique_ptr<storage::PgMapCatalog> catalog_;
  std::unique_ptr<MapDirectory> maps_;
  std::unique_ptr<MapOwnership> ownership_;  // PostgreSQL only; goes before maps_
  std::unique_ptr<MapForwarder> forwarder_;  // PostgreSQL with forwarding only
  std::unique_ptr<MapRouter> router_;
  std::mutex lifecycle_mu_;  // one DeleteMap or RestoreMap at a time
  CallsInProgress calls_;    // before server_: its interceptors point here
  std::unique_ptr<grpc::Server> server_;
  int port_ = 0;
  int health_port_ = 0;
  std::mutex health_mu_;    // shut_down_ and the health status
  bool shut_down_ = false;  // GUARDED_BY(health_mu_)
  std::thread housekeeping_;
  std::mutex housekeeping_mu_;
  std::condition_variable housekeeping_cv_;
  bool housekeeping_stop_ = false;  // GUARDED_BY(housekeeping_mu_)
};

}  // namespace mapd::service

#endif  // MAPD_SERVICE_SERVER_H_
