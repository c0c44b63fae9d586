#include "service/map_ownership.h"

#include <chrono>

#include "service/log.h"
#include "service/rendezvous.h"
#include "storage/postgres/store.h"

namespace mapd::service {

StatusOr<std::unique_ptr<MapOwnership>> MapOwnership::Create(const OwnershipOptions& options,
                                                             MapDirectory* maps,
                                                             storage::PgMapCatalog* catalog,
                                                             Hooks hooks) {
  std::unique_ptr<MapOwnership> o(new MapOwnership(options, maps, catalog, std::move(hooks)));
  StatusOr<storage::PgConnection> conn = storage::PgConnection::Connect(options.conninfo);
  if (!conn.ok()) return conn.status();
  o->conn_ = std::move(conn).value();
  // A renewal waits for the map's open write transaction (the fence's row
  // lock); never for longer than this, so that one stuck map cannot starve
  // the others' renewals.
  MAPD_RETURN_IF_ERROR(o->conn_.Exec("SET lock_timeout = '1s'"));
  return o;
}

MapOwnership::~MapOwnership() { Stop(); }

Status MapOwnership::RunOnce() {
  std::lock_guard<std::mutex> lock(round_mu_);
  if (!conn_.healthy() || !conn_.Exec("SELECT 1").ok()) {
    StatusOr<storage::PgConnection> again = storage::PgConnection::Connect(options_.conninfo);
    if (!again.ok()) return again.status();
    conn_ = std::move(again).value();
    MAPD_RETURN_IF_ERROR(conn_.Exec("SET lock_timeout = '1s'"));
  }
  MAPD_RETURN_IF_ERROR(storage::HeartbeatInstance(conn_, options_.instance, options_.lease_ttl_s));
  RenewServed();
  return TakeFree();
}

void MapOwnership::RenewServed() {
  for (const MapHold& map : maps_->List()) {
    auto* store = dynamic_cast<storage::PgStore*>(&map->core->store());
    if (store == nullptr) continue;
    Status lost;
    if (!store->owner()) {
      // The write fence found the map taken over (its writes are refused),
      // or a reconnect found the engine out of step (PgObservationLog::
      // Reconnect); either way the map is dropped here, and in the second
      // case opened again by the next round (its lease is still this one's).
      lost = Status::FailedPrecondition(
          "map '" + map->id +
          "': its store gave it up (a write found its lease taken over by another mapd, or a "
          "lost commit answer left the fused map behind the database)");
    } else if (const double busy_s = map->core->WriterBusyForS();
               busy_s > options_.lease_ttl_s / 2) {
      // A writer stuck in the database serves nobody: let the lease lapse
      // rather than hold the map. If it recovers first, the next round renews.
      Log(LogLevel::kWarn, "lease_not_renewed",
          {{"map", map->id}, {"writer_busy_s", std::to_string(busy_s)}});
      continue;
    } else {
      Status renewed = storage::RenewMapLease(conn_, store->lease(), options_.lease_ttl_s);
      if (renewed.code() == StatusCode::kFailedPrecondition) {
        lost = renewed;
      } else if (!renewed.ok()) {
        Log(LogLevel::kWarn, "lease_renewal_failed",
            {{"map", map->id}, {"error", renewed.ToString()}});
        continue;
      }
    }
    if (lost.ok()) continue;
    hooks_.drop(map->id, lost);
    // Not here any more, and who has it is learnt next round: "being taken
    // over" until then rather than a redirect to this instance.
    std::lock_guard<std::mutex> lock(view_mu_);
    view_[map->id] = MapOwner{};
  }
}

Status MapOwnership::TakeFree() {
  StatusOr<std::vector<std::string>> ids = catalog_->ListMaps();
  if (!ids.ok()) return ids.status();
  StatusOr<std::vector<storage::LeaseRow>> leases = storage::ListMapLeases(conn_);
  if (!leases.ok()) return leases.status();
  StatusOr<std::vector<storage::InstanceRow>> live = storage::LiveInstances(conn_);
  if (!live.ok()) return live.status();
  std::vector<std::string> names;
  for (const storage::InstanceRow& i : *live) names.push_back(i.name);
  std::map<std::string, storage::LeaseRow> by_map;
  for (storage::LeaseRow& l : *leases) by_map[l.map_id] = std::move(l);

  std::map<std::string, MapOwner> view;
  const std::string& me = options_.instance.name;
  for (const std::string& id : *ids) {
    auto lease = by_map.find(id);
    const bool has_lease = lease != by_map.end();
    if (has_lease) {
      view[id] =
          MapOwner{lease->second.owner, lease->second.address, lease->second.expires_in_s > 0};
    } else {
      view[id] = MapOwner{};
    }
    if (maps_->FindCore(id) != nullptr) continue;  // served here
    // A lease of this instance for a map it does not serve (dropped, handed
    // off): never a redirect to itself.
    if (view[id].instance == me) view[id].live = false;
    if (!taking_) continue;  // stopping
    const bool lease_live = has_lease && lease->second.expires_in_s > 0;
    if (lease_live && lease->second.owner != me) continue;
    // Its own live lease: this instance restarted (same name). A lapsed one
    // of its own it released (a handoff), and takes back only as any other.
    const bool mine = (lease_live && lease->second.owner == me) || RendezvousPick(id, names) == me;
    const double lapsed_for_s = has_lease ? -lease->second.expires_in_s : 1e9;
    if (!mine && lapsed_for_s < options_.lease_ttl_s) continue;  // its chosen one may take it
    {
      std::lock_guard<std::mutex> lock(view_mu_);
      if (leaving_.count(id) != 0) continue;  // being deleted here
    }
    Status opened = hooks_.open(id);
    if (opened.ok()) {
      view[id] = MapOwner{me, options_.instance.address, true};
    } else {
      Log(LogLevel::kInfo, "map_not_taken", {{"map", id}, {"why", opened.ToString()}});
    }
  }
  if (taking_) {
    if (auto hand = PickHandOff(*live)) {
      const auto& [id, to] = *hand;
      if (Status s = hooks_.hand_off(id); s.ok()) {
        Log(LogLevel::kInfo, "map_handed_off",
            {{"map", id}, {"to", to.instance}, {"address", to.address}});
        view[id] = MapOwner{to.instance, to.address, false};  // until it has taken the map
        // The handoff drained and stopped a map, which may take a while: the
        // other maps' leases must not lapse meanwhile.
        RenewServed();
      } else {
        Log(LogLevel::kWarn, "map_hand_off_failed", {{"map", id}, {"error", s.ToString()}});
      }
    }
  }
  std::lock_guard<std::mutex> lock(view_mu_);
  view_ = std::move(view);
  return Status::Ok();
}

std::optional<std::pair<std::string, MapOwner>> MapOwnership::PickHandOff(
    const std::vector<storage::InstanceRow>& live) const {
  std::vector<std::string> names;
  for (const storage::InstanceRow& i : live) names.push_back(i.name);
  for (const MapHold& map : maps_->List()) {
    const std::string pick = RendezvousPick(map->id, names);
    if (pick.empty() || pick == options_.instance.name) continue;
    for (const storage::InstanceRow& i : live) {
      if (i.name == pick && i.alive_for_s >= 2 * options_.lease_ttl_s) {
        return std::make_pair(map->id, MapOwner{i.name, i.address, true});
      }
    }
  }
  return std::nullopt;
}

void MapOwnership::StartThread() {
  thread_ = std::thread([this] { Loop(); });
}

void MapOwnership::Loop() {
  const auto period = std::chrono::duration<double>(options_.lease_ttl_s / 4);
  std::unique_lock<std::mutex> lock(stop_mu_);
  while (!stop_cv_.wait_for(lock, period, [this] { return stop_; })) {
    lock.unlock();
    if (Status s = RunOnce(); !s.ok()) {
      Log(LogLevel::kWarn, "ownership_round_failed", {{"error", s.ToString()}});
    }
    lock.lock();
  }
}

void MapOwnership::Stop() {
  {
    std::lock_guard<std::mutex> lock(stop_mu_);
    if (stop_) return;
    stop_ = true;
  }
  stop_cv_.notify_all();
  if (thread_.joinable()) thread_.join();
  std::lock_guard<std::mutex> lock(round_mu_);
  (void)storage::LeaveInstance(conn_, options_.instance);
}

std::map<std::string, MapOwner> MapOwnership::Owners() {
  {
    // Read now: a map made on another instance a moment ago is listed.
    std::lock_guard<std::mutex> lock(lookup_mu_);
    StatusOr<std::vector<std::string>> ids = catalog_->ListMaps();
    StatusOr<std::vector<storage::LeaseRow>> leases =
        Status::Unavailable("cannot connect to PostgreSQL");
    if (ids.ok() && ConnectLookupLocked()) leases = storage::ListMapLeases(lookup_conn_);
    if (leases.ok()) {
      std::map<std::string, MapOwner> owners;
      for (const std::string& id : *ids) owners[id] = MapOwner{};
      for (const storage::LeaseRow& l : *leases) {
        if (owners.count(l.map_id) != 0) {
          owners[l.map_id] = MapOwner{l.owner, l.address, l.expires_in_s > 0};
        }
      }
      return owners;
    }
  }
  std::lock_guard<std::mutex> lock(view_mu_);  // the database is away: as last seen
  return view_;
}

bool MapOwnership::ConnectLookupLocked() {
  if (lookup_conn_.healthy()) return true;
  StatusOr<storage::PgConnection> c = storage::PgConnection::Connect(options_.conninfo);
  if (!c.ok()) return false;
  lookup_conn_ = std::move(c).value();
  return true;
}

std::optional<MapOwner> MapOwnership::LocateNow(const std::string& id) {
  std::optional<MapOwner> seen = Locate(id);
  // A map the last round did not see may have been made since, on another
  // instance (or no round has finished yet): ask the database.
  std::lock_guard<std::mutex> lock(lookup_mu_);
  if (!ConnectLookupLocked()) return seen;
  StatusOr<storage::LeaseRow> row = storage::GetMapLease(lookup_conn_, id);
  if (!row.ok()) {
    if (seen || row.status().code() != StatusCode::kNotFound) return seen;
    // No lease: a map nobody has taken yet, or no such map.
    if (!catalog_->Settings(id).ok()) return std::nullopt;
    return MapOwner{};
  }
  // A lease of a map that is not listed: archived (held by nobody, for
  // ever) or being imported. Neither is served anywhere.
  if (catalog_->Settings(id).status().code() == StatusCode::kNotFound) {
    Forget(id);
    return std::nullopt;
  }
  MapOwner now{row->owner, row->address, row->expires_in_s > 0};
  if (now.live) {
    std::lock_guard<std::mutex> view_lock(view_mu_);
    view_[id] = now;
  }
  return now;
}

void MapOwnership::Forget(const std::string& id) {
  std::lock_guard<std::mutex> lock(view_mu_);
  view_.erase(id);
}

void MapOwnership::MarkLeaving(const std::string& id, bool leaving) {
  std::lock_guard<std::mutex> lock(view_mu_);
  if (leaving) {
    leaving_.insert(id);
  } else {
    leaving_.erase(id);
  }
}

std::optional<MapOwner> MapOwnership::Locate(const std::string& id) const {
  std::lock_guard<std::mutex> lock(view_mu_);
  auto it = view_.find(id);
  if (it == view_.end()) return std::nullopt;
  return it->second;
}

}  // namespace mapd::service
