// MapServer: MapCore + the gRPC server around it (health, reflection, TLS).
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
#include "service/map_service.h"

namespace mapd::service {

class MapServer {
 public:
  // Opens the database and starts listening at once. The fused map is
  // recovered in the background (MapCore::Open): until then the health
  // service says NOT_SERVING and map RPCs answer UNAVAILABLE; then SERVING
  // and an `event=serving` log line.
  static StatusOr<std::unique_ptr<MapServer>> Start(const ServerConfig& config);
  // Waits until the map is recovered; false on timeout or failed recovery.
  bool WaitUntilServing(std::chrono::duration<double> timeout) const;
  ~MapServer();

  // The port actually bound (useful with port 0).
  int port() const { return port_; }
  // The port of health_listen (0 when it is not set).
  int health_port() const { return health_port_; }
  std::string address() const;
  // The core, for what runs beside the gRPC server (the web view).
  Core* core() const { return core_.get(); }
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

 private:
  MapServer() = default;
  // SERVING once the map is recovered, while the database takes writes and
  // until Shutdown(). REQUIRES: health_mu_ held.
  void UpdateHealthLocked();
  void Housekeeping();  // every second: idle uploads, log summaries, memory trim
  void StopHousekeeping();

  ServerConfig config_;
  AuthOptions auth_;
  std::unique_ptr<MapCore> core_;
  std::unique_ptr<MapServiceImpl> service_;
  CallsInProgress calls_;  // before server_: its interceptors point here
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
