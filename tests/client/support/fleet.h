// A fleet of mapd processes on one PostgreSQL database, for the benchmarks
// that drive several instances (failover_bench, fleet_soak_bench): started
// with `--store` and an instance name each, maps made through mapctl, and
// each map's owner asked with LocateMap. The including target defines
// MAPD_BINARY and MAPCTL_BINARY.
#ifndef MAPD_TESTS_CLIENT_SUPPORT_FLEET_H_
#define MAPD_TESTS_CLIENT_SUPPORT_FLEET_H_

#include <grpcpp/grpcpp.h>
#include <libpq-fe.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "client/support/streaming_robot.h"
#include "common/postgres.h"
#include "common/process.h"
#include "common/temp_dir.h"
#include "mapserver/v1/map_service.grpc.pb.h"
#include "service/rendezvous.h"

namespace mapd::testing {

struct Fleet {
  std::unique_ptr<PostgresCluster> cluster;
  std::string store;               // the database's connection string
  std::vector<std::string> extra;  // more mapd flags, e.g. --lease_ttl_s
  TempDir dir;
  std::vector<MapdProcess> mapd;
  std::vector<std::string> addresses, names;

  // Starts a PostgreSQL (fsync on) and makes the fleet's database; false
  // (with the reason on stderr) when it cannot.
  bool StartDatabase() {
    std::string why;
    cluster = PostgresCluster::Start(/*fsync=*/true, &why);
    if (cluster == nullptr) {
      std::fprintf(stderr, "no PostgreSQL: %s\n", why.c_str());
      return false;
    }
    store = cluster->NewDatabase();
    return true;
  }

  // Starts `n` instances named mapd-1.. on free ports; false (with the log
  // on stderr) when one does not come up.
  bool Launch(int n) {
    for (int i = 0; i < n; ++i) {
      names.push_back("mapd-" + std::to_string(i + 1));
      mapd.push_back(Start(i, "127.0.0.1:0"));
      if (mapd.back().port == 0) {
        std::fprintf(stderr, "mapd did not start:\n%s\n", mapd.back().log().c_str());
        return false;
      }
      addresses.push_back(mapd.back().address);
    }
    return true;
  }

  // Instance `i` (again, after it stopped: same name; `listen` its address).
  MapdProcess Start(int i, const std::string& listen) {
    std::vector<std::string> args = {"--store", store,      "--instance_name",
                                     names[i],  "--listen", listen};
    args.insert(args.end(), extra.begin(), extra.end());
    return StartMapd("", args, MAPD_BINARY, std::chrono::seconds(60), "listening",
                     dir.File(names[i] + ".log"));
  }

  // "default" and n - 1 maps "site-1".. made with mapctl; empty on failure.
  std::vector<std::string> CreateMaps(int n) {
    std::vector<std::string> maps = {"default"};
    for (int i = 1; i < n; ++i) {
      maps.push_back("site-" + std::to_string(i));
      CommandResult r =
          RunCommand({MAPCTL_BINARY, "--server", addresses[0], "maps", "create", maps.back()}, "",
                     std::chrono::seconds(60));
      if (r.exit_code != 0) {
        std::fprintf(stderr, "maps create: %s\n", r.err.c_str());
        return {};
      }
    }
    return maps;
  }

  // The address serving `map`, as the first instance that answers says;
  // empty while nobody does.
  std::string Owner(const std::string& map) const {
    for (const std::string& address : addresses) {
      auto stub = mapserver::v1::MapService::NewStub(Connect(address));
      grpc::ClientContext call;
      call.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(2));
      mapserver::v1::LocateMapRequest request;
      request.set_map_id(map);
      mapserver::v1::MapLocation where;
      if (stub->LocateMap(&call, request, &where).ok()) return where.live() ? where.address() : "";
    }
    return "";
  }

  // Every map served by the instance rendezvous hashing picks for it.
  bool Spread(const std::vector<std::string>& maps) const {
    for (const std::string& map : maps) {
      const std::string want = service::RendezvousPick(map, names);
      const size_t i =
          static_cast<size_t>(std::find(names.begin(), names.end(), want) - names.begin());
      if (Owner(map) != addresses[i]) return false;
    }
    return true;
  }

  // Seconds until Spread(maps), or -1 after timeout_s.
  double WaitSpread(const std::vector<std::string>& maps, double timeout_s) const {
    const auto start = std::chrono::steady_clock::now();
    auto seconds = [&] {
      return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    };
    while (!Spread(maps)) {
      if (seconds() > timeout_s) return -1.0;
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
    }
    return seconds();
  }

  // Sessions open on the fleet's database (pg_stat_activity), this one's
  // included; -1 when it cannot be asked.
  int DatabaseSessions() const {
    PGconn* conn = PQconnectdb(store.c_str());
    PGresult* r =
        PQexec(conn, "SELECT count(*) FROM pg_stat_activity WHERE datname = current_database()");
    const int n = PQresultStatus(r) == PGRES_TUPLES_OK ? std::atoi(PQgetvalue(r, 0, 0)) : -1;
    PQclear(r);
    PQfinish(conn);
    return n;
  }

  // The batches map `map` stored per robot (ListRobots at its owner); empty
  // when it cannot be asked.
  std::vector<std::pair<std::string, uint64_t>> StoredBatches(const std::string& map) const {
    auto stub = mapserver::v1::MapService::NewStub(Connect(Owner(map)));
    grpc::ClientContext call;
    call.AddMetadata("mapd-map-id", map);
    call.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(10));
    mapserver::v1::ListRobotsResponse listed;
    std::vector<std::pair<std::string, uint64_t>> out;
    if (!stub->ListRobots(&call, mapserver::v1::ListRobotsRequest(), &listed).ok()) return out;
    for (const auto& r : listed.robots()) out.emplace_back(r.robot_id(), r.batches());
    return out;
  }
};

}  // namespace mapd::testing

#endif  // MAPD_TESTS_CLIENT_SUPPORT_FLEET_H_
