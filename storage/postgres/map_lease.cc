#include "storage/postgres/map_lease.h"

#include <unistd.h>

#include <cstdio>

namespace mapd::storage {
namespace {

PgParams LeaseParams(const MapLease& lease) {
  PgParams p;
  p.Text(lease.map_id).Text(lease.owner).Int(lease.epoch);
  return p;
}

// "instance N (at ADDRESS)", for messages.
std::string Describe(const LeaseRow& row) {
  return "instance '" + row.owner + "' (" + (row.address.empty() ? "no address" : row.address) +
         ", epoch " + std::to_string(row.epoch) + ")";
}

// Why `lease` is no longer held, naming who holds the map now.
Status Lost(PgConnection& conn, const MapLease& lease) {
  StatusOr<LeaseRow> now = GetMapLease(conn, lease.map_id);
  std::string who = "nobody";
  if (now.ok()) who = Describe(*now);
  if (!now.ok() && now.status().code() != StatusCode::kNotFound) who = now.status().message();
  return Status::FailedPrecondition("map '" + lease.map_id + "': this instance's lease (epoch " +
                                    std::to_string(lease.epoch) + ") was taken over; " + who +
                                    " serves the map now");
}

constexpr const char* kLeaseColumns =
    "SELECT map, owner, address, epoch, extract(epoch FROM expires_at - clock_timestamp())::float8 "
    "FROM map_leases ";

LeaseRow LeaseAt(const PgResult& r, int row) {
  LeaseRow l;
  l.map_id = std::string(r.Bytes(row, 0));
  l.owner = std::string(r.Bytes(row, 1));
  l.address = std::string(r.Bytes(row, 2));
  l.epoch = r.Int(row, 3);
  l.expires_in_s = r.Double(row, 4);
  return l;
}

}  // namespace

PgInstance DefaultPgInstance() {
  char host[256] = {};
  if (::gethostname(host, sizeof host - 1) != 0) host[0] = '\0';
  return PgInstance{std::string(host) + "/" + std::to_string(::getpid()), ""};
}

StatusOr<MapLease> AcquireMapLease(PgConnection& conn, const std::string& map_id,
                                   const PgInstance& me, double ttl_s) {
  PgParams p;
  p.Text(map_id).Text(me.name).Text(me.address).Double(ttl_s);
  // ON CONFLICT ... WHERE is checked on the newest row version, under its
  // lock: of two instances taking a lapsed lease together, one gets it.
  // clock_timestamp(), not now() (the statement's start): the take may wait
  // for the owner's open transaction (FenceMapLease), and the lease counts
  // from when it is taken.
  StatusOr<PgResult> r = conn.Query(
      "INSERT INTO map_leases AS l (map, owner, address, epoch, expires_at) "
      "VALUES ($1, $2, $3, 1, clock_timestamp() + make_interval(secs => $4)) "
      "ON CONFLICT (map) DO UPDATE SET owner = EXCLUDED.owner, address = EXCLUDED.address, "
      "epoch = l.epoch + 1, expires_at = EXCLUDED.expires_at "
      "WHERE l.expires_at <= clock_timestamp() OR l.owner = EXCLUDED.owner RETURNING epoch",
      p);
  if (!r.ok()) return r.status();
  if (r->rows() == 1) return MapLease{map_id, me.name, r->Int(0, 0)};
  StatusOr<LeaseRow> held = GetMapLease(conn, map_id);
  if (!held.ok()) return held.status();
  char left[32];
  std::snprintf(left, sizeof left, "%.1f", held->expires_in_s);
  return Status::FailedPrecondition("map '" + map_id + "' is served by " + Describe(*held) +
                                    "; its lease runs " + left + " s more");
}

Status RenewMapLease(PgConnection& conn, const MapLease& lease, double ttl_s) {
  PgParams p = LeaseParams(lease);
  p.Double(ttl_s);
  StatusOr<PgResult> r = conn.Query(
      "UPDATE map_leases SET expires_at = clock_timestamp() + make_interval(secs => $4) "
      "WHERE map = $1 AND owner = $2 AND epoch = $3",
      p);
  if (!r.ok()) return r.status();
  return r->affected() == 1 ? Status::Ok() : Lost(conn, lease);
}

Status ReleaseMapLease(PgConnection& conn, const MapLease& lease) {
  StatusOr<PgResult> r = conn.Query(
      "UPDATE map_leases SET expires_at = clock_timestamp() WHERE map = $1 AND owner = $2 AND "
      "epoch = $3",
      LeaseParams(lease));
  return r.ok() ? Status::Ok() : r.status();
}

Status FenceMapLease(PgConnection& conn, const MapLease& lease) {
  PgParams p;
  p.Text(lease.map_id);
  // FOR SHARE, not FOR KEY SHARE: it must conflict with a take's UPDATE of
  // the epoch, so that the take waits for this transaction.
  StatusOr<PgResult> r =
      conn.Query("SELECT owner, epoch FROM map_leases WHERE map = $1 FOR SHARE", p);
  if (!r.ok()) return r.status();
  if (r->rows() == 1 && r->Bytes(0, 0) == lease.owner && r->Int(0, 1) == lease.epoch) {
    return Status::Ok();
  }
  return Lost(conn, lease);
}

StatusOr<std::vector<LeaseRow>> ListMapLeases(PgConnection& conn) {
  StatusOr<PgResult> r = conn.Query(std::string(kLeaseColumns) + "ORDER BY map");
  if (!r.ok()) return r.status();
  std::vector<LeaseRow> out;
  for (int i = 0; i < r->rows(); ++i) out.push_back(LeaseAt(*r, i));
  return out;
}

StatusOr<LeaseRow> GetMapLease(PgConnection& conn, const std::string& map_id) {
  PgParams p;
  p.Text(map_id);
  StatusOr<PgResult> r = conn.Query(std::string(kLeaseColumns) + "WHERE map = $1", p);
  if (!r.ok()) return r.status();
  if (r->rows() == 0) return Status::NotFound("map '" + map_id + "' has no owner yet");
  return LeaseAt(*r, 0);
}

Status HeartbeatInstance(PgConnection& conn, const PgInstance& me, double ttl_s) {
  PgParams p;
  p.Text(me.name).Text(me.address).Double(ttl_s);
  StatusOr<PgResult> r = conn.Query(
      "INSERT INTO instances AS i (name, address, since, expires_at) "
      "VALUES ($1, $2, clock_timestamp(), clock_timestamp() + make_interval(secs => $3)) "
      "ON CONFLICT (name) DO UPDATE SET address = EXCLUDED.address, "
      "expires_at = EXCLUDED.expires_at, "
      "since = CASE WHEN i.expires_at <= clock_timestamp() THEN clock_timestamp() ELSE i.since END",
      p);
  return r.ok() ? Status::Ok() : r.status();
}

Status LeaveInstance(PgConnection& conn, const PgInstance& me) {
  PgParams p;
  p.Text(me.name);
  StatusOr<PgResult> r = conn.Query("DELETE FROM instances WHERE name = $1", p);
  return r.ok() ? Status::Ok() : r.status();
}

StatusOr<std::vector<InstanceRow>> LiveInstances(PgConnection& conn) {
  StatusOr<PgResult> r = conn.Query(
      "SELECT name, address, extract(epoch FROM clock_timestamp() - since)::float8 FROM instances "
      "WHERE expires_at > clock_timestamp() ORDER BY name");
  if (!r.ok()) return r.status();
  std::vector<InstanceRow> out;
  for (int i = 0; i < r->rows(); ++i) {
    out.push_back({std::string(r->Bytes(i, 0)), std::string(r->Bytes(i, 1)), r->Double(i, 2)});
  }
  return out;
}

}  // namespace mapd::storage
