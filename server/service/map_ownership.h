// MapOwnership: which maps of a shared PostgreSQL database this mapd serves
// (docs/scale-out.md, "3. Ownership and failover"). Any instance can serve
// any map; exactly one does at a time, by the map's lease
// (storage/postgres/map_lease.h).
//
// A thread runs a round every lease_ttl_s / 4:
//   - heartbeat: this instance is live for another lease_ttl_s;
//   - renew the lease of each map served here, but only while its writer
//     makes progress (a writer stuck in the database for half a lease gives
//     the map up rather than hold it unserved); a lease found taken over (by
//     the renewal or by the write fence) drops the map here;
//   - take maps without a live lease: those rendezvous hashing over the live
//     instances gives to this one at once, any other once its lease has
//     lapsed for a whole lease_ttl_s more (its chosen instance is not taking
//     it). A restarted instance takes its own maps back at once.
//   - hand one map per round to the instance rendezvous hashing gives it,
//     once that one has been live for two leases (so that a restarting or
//     flapping instance does not pull maps back and forth): maps spread
//     over the live instances, and come back to a restarted one.
//
// The round's view of the leases answers Locate(): where a map not served
// here is, for redirects, without a database query per call.
//
// Thread safety: every method may be called from any thread.
#ifndef MAPD_SERVICE_MAP_OWNERSHIP_H_
#define MAPD_SERVICE_MAP_OWNERSHIP_H_

#include <atomic>
#include <condition_variable>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include "common/status.h"
#include "service/map_directory.h"
#include "service/map_locator.h"
#include "storage/postgres/map_catalog.h"
#include "storage/postgres/map_lease.h"

namespace mapd::service {

struct OwnershipOptions {
  std::string conninfo;
  storage::PgInstance instance;  // name and advertised address
  double lease_ttl_s = 3.0;
};

class MapOwnership final : public MapLocator {
 public:
  struct Hooks {
    // Opens map `id` here, taking its lease (MapDirectory).
    std::function<Status(const std::string& id)> open;
    // Stops serving map `id`: its lease is lost (`why`).
    std::function<void(const std::string& id, const Status& why)> drop;
    // Hands map `id` to another instance: stops serving it here (streams
    // drained, what is queued committed) and releases its lease.
    std::function<Status(const std::string& id)> hand_off;
  };

  // Connects; no round runs yet.
  static StatusOr<std::unique_ptr<MapOwnership>> Create(const OwnershipOptions& options,
                                                        MapDirectory* maps,
                                                        storage::PgMapCatalog* catalog,
                                                        Hooks hooks);
  // Stop() first.
  ~MapOwnership() override;

  // One round now (at start: a lone instance serves its maps before it
  // answers anything), then a round every lease_ttl_s / 4 on a thread.
  Status RunOnce();
  void StartThread();
  // Ends the rounds and removes this instance from the live ones; the maps'
  // leases are released as their stores close.
  void Stop();

  // MapLocator. Locate: as of the last round (maps served here: this
  // instance, live). LocateNow and Owners: read from the database.
  std::optional<MapOwner> Locate(const std::string& id) const override;
  std::optional<MapOwner> LocateNow(const std::string& id) override;
  // Map `id` is no longer in the database's list (archived or deleted
  // here): Locate forgets it until a round sees it again.
  void Forget(const std::string& id);
  // While DeleteMap stops map `id` here, its lease is still this
  // instance's: rounds must not open it again meanwhile.
  void MarkLeaving(const std::string& id, bool leaving);
  std::map<std::string, MapOwner> Owners() override;
  int retry_after_ms() const override { return static_cast<int>(options_.lease_ttl_s * 250); }
  // Who this instance is; before the first round (the port is known late).
  void set_instance(storage::PgInstance instance) { options_.instance = std::move(instance); }
  const storage::PgInstance& instance() const { return options_.instance; }
  // Shutting down: rounds go on renewing the maps served here while they
  // drain, but take no more.
  void StopTaking() { taking_ = false; }

 private:
  MapOwnership(OwnershipOptions options, MapDirectory* maps, storage::PgMapCatalog* catalog,
               Hooks hooks)
      : options_(std::move(options)), maps_(maps), catalog_(catalog), hooks_(std::move(hooks)) {}
  void RenewServed();
  // Takes free maps, hands one off (above) and refreshes view_.
  Status TakeFree();
  // The map served here to hand off this round, if any, and to whom.
  std::optional<std::pair<std::string, MapOwner>> PickHandOff(
      const std::vector<storage::InstanceRow>& live) const;
  void Loop();
  // lookup_conn_, connected if it was not; false when it cannot be.
  bool ConnectLookupLocked();

  OwnershipOptions options_;  // instance: set before the thread starts
  std::atomic<bool> taking_{true};
  MapDirectory* const maps_;
  storage::PgMapCatalog* const catalog_;
  const Hooks hooks_;
  storage::PgConnection conn_;  // the rounds' (one at a time: round_mu_)
  std::mutex round_mu_;
  storage::PgConnection lookup_conn_;  // LocateNow's and Owners', under lookup_mu_
  std::mutex lookup_mu_;

  mutable std::mutex view_mu_;
  std::map<std::string, MapOwner> view_;  // GUARDED_BY(view_mu_): every map of the database
  std::set<std::string> leaving_;         // GUARDED_BY(view_mu_): MarkLeaving

  std::mutex stop_mu_;
  std::condition_variable stop_cv_;
  bool stop_ = false;  // GUARDED_BY(stop_mu_)
  std::thread thread_;
};

}  // namespace mapd::service

#endif  // MAPD_SERVICE_MAP_OWNERSHIP_H_
