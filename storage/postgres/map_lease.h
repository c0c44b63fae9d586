// Map ownership on a shared PostgreSQL database (docs/scale-out.md, "3.
// Ownership and failover"): exactly one mapd instance writes a map at a time.
//
// A map's lease row names its owner, the address clients reach it at, and an
// epoch, the fencing token: every take of the lease adds one. Time is the
// database's clock (now()), never a host's, so hosts whose clocks disagree
// still agree on who owns what. The owner renews the lease while its writer
// makes progress; when it lapses another instance may take the map.
//
// Safety does not rest on timing: every write transaction of a map first
// runs FenceMapLease, which locks the lease row (FOR SHARE) and checks the
// epoch. A take (an UPDATE of the row) therefore waits for the owner's open
// transaction, and once it committed, the old owner's next transaction is
// refused. A paused owner ("zombie") that wakes after a takeover can never
// commit, and no row of an old epoch follows the new epoch's first. The
// writer's session has idle_in_transaction_session_timeout set, so a paused
// owner's open transaction cannot hold a takeover back for long.
//
// Functions run statements on `conn` and need no transaction of their own.
#ifndef MAPD_STORAGE_POSTGRES_MAP_LEASE_H_
#define MAPD_STORAGE_POSTGRES_MAP_LEASE_H_

#include <cstdint>
#include <string>
#include <vector>

#include "common/status.h"
#include "storage/postgres/pq.h"

namespace mapd::storage {

// One mapd instance. `name` stays the same across restarts (mapd: its
// advertised address), so that a restarted instance takes its maps back at
// once instead of waiting for their leases to lapse; `address` is where
// clients reach it (host:port), for redirects.
struct PgInstance {
  std::string name;
  std::string address;
};

// "<hostname>/<pid>": unique per process, for tools and tests.
PgInstance DefaultPgInstance();

// A lease held: the fence of the holder's write transactions.
struct MapLease {
  std::string map_id;
  std::string owner;  // PgInstance::name
  int64_t epoch = 0;
};

struct LeaseRow {
  std::string map_id;
  std::string owner;
  std::string address;
  int64_t epoch = 0;
  double expires_in_s = 0;  // negative once lapsed
};

struct InstanceRow {
  std::string name;
  std::string address;
  double alive_for_s = 0;  // since this run's first heartbeat
};

// Takes `map_id`'s lease for `me` for `ttl_s` seconds: when it has none,
// when it lapsed, or when it is `me`'s already (a restarted instance). The
// epoch grows by one. FailedPrecondition naming the owner and its address
// while another instance holds it; the map must exist (EnsureMap).
StatusOr<MapLease> AcquireMapLease(PgConnection& conn, const std::string& map_id,
                                   const PgInstance& me, double ttl_s);
// Extends `lease` to now + ttl_s, also after it lapsed, as long as nobody
// took it. FailedPrecondition naming the new owner once one did.
Status RenewMapLease(PgConnection& conn, const MapLease& lease, double ttl_s);
// Lets the lease lapse now, so another instance may take the map at once.
// Ok when it was lost already.
Status ReleaseMapLease(PgConnection& conn, const MapLease& lease);
// In a write transaction, before its first write: locks the lease row until
// the transaction ends; FailedPrecondition naming the new owner when the
// epoch is no longer `lease`'s (the transaction must roll back).
Status FenceMapLease(PgConnection& conn, const MapLease& lease);
// Every lease, by map.
StatusOr<std::vector<LeaseRow>> ListMapLeases(PgConnection& conn);
// One map's lease; NotFound when it never had an owner.
StatusOr<LeaseRow> GetMapLease(PgConnection& conn, const std::string& map_id);

// `me` is alive for another ttl_s seconds.
Status HeartbeatInstance(PgConnection& conn, const PgInstance& me, double ttl_s);
// `me` stops: its row goes, and it is no longer counted live.
Status LeaveInstance(PgConnection& conn, const PgInstance& me);
// The instances whose heartbeat has not lapsed, by name.
StatusOr<std::vector<InstanceRow>> LiveInstances(PgConnection& conn);

}  // namespace mapd::storage

#endif  // MAPD_STORAGE_POSTGRES_MAP_LEASE_H_
