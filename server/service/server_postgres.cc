// MapServer's side of a shared PostgreSQL database (docs/scale-out.md): the
// server-wide parts, who this instance is, and opening, handing off and
// dropping maps as MapOwnership decides.
#include <unistd.h>

#include <algorithm>

#include "common/clock.h"
#include "service/log.h"
#include "service/server.h"
#include "service/server_wide_core.h"
#include "storage/postgres/store.h"

namespace mapd::service {

StatusOr<ServerWide> MapServer::OpenServerWide() {
  // The default map's store without its lease: tokens and audit rows only.
  storage::PgOwnership not_owner;
  not_owner.own = false;
  StatusOr<std::unique_ptr<storage::PgStore>> store =
      storage::PgStore::Open(config_.store, kDefaultMapId, CoreOptions(config_).store, not_owner);
  if (!store.ok()) return Status(store.status().code(), "store: " + store.status().message());
  ServerWide w;
  w.core = std::make_unique<ServerWideCore>(std::move(store).value());
  w.service = std::make_unique<MapServiceImpl>(w.core.get(), config_.ingest, config_.submaps,
                                               config_.streams, auth_,
                                               MapPlacement{kDefaultMapId, nullptr});
  return w;
}

storage::PgInstance MapServer::Instance() const {
  storage::PgInstance me;
  me.address = config_.advertise_address;
  if (me.address.empty()) {
    std::string host = config_.listen.substr(0, config_.listen.rfind(':'));
    if (host.empty() || host == "0.0.0.0" || host == "[::]") {
      char name[256] = {};
      if (::gethostname(name, sizeof name - 1) == 0) host = name;
    }
    me.address = host + ":" + std::to_string(port_);
  }
  me.name = config_.instance_name.empty() ? me.address : config_.instance_name;
  return me;
}

Status MapServer::TakeMap(const std::string& id) {
  {
    std::lock_guard<std::mutex> lock(health_mu_);
    if (shut_down_) return Status::Unavailable("mapd is shutting down");
  }
  StatusOr<MapHold> map = maps_->Serve(id);
  if (!map.ok()) return map.status();
  auto* store = dynamic_cast<storage::PgStore*>(&(*map)->core->store());
  Log(LogLevel::kInfo, "map_taken",
      {{"map", id}, {"epoch", store ? std::to_string(store->lease().epoch) : "?"}});
  WatchMap(map->get());
  return Status::Ok();
}

namespace {

// What a call still holding a map that moved elsewhere gets: the map's
// connections are closed (a retired map holds none), and a new call is
// redirected to the owner.
Status Served(const std::string& id, const std::string& how) {
  return Status::Unavailable("map '" + id + "' is no longer served here (" + how +
                             "); call again: you will be sent to its owner");
}

}  // namespace

Status MapServer::HandOffMap(const std::string& id) {
  MapHold map = maps_->Retire(id);
  if (map == nullptr) return Status::NotFound("map '" + id + "' is not served here");
  map->service->StartDraining();  // streams end UNAVAILABLE; robots go to the new owner
  map->core->Stop();              // commits what is queued, writes a snapshot
  {
    std::lock_guard<std::mutex> lock(health_mu_);
    server_->GetHealthCheckService()->SetServingStatus("map/" + id, false);
    UpdateHealthLocked();
  }
  auto* store = dynamic_cast<storage::PgStore*>(&map->core->store());
  if (store == nullptr) return Status::Ok();
  Status released = store->ReleaseLease();
  store->Close(Served(id, "handed to another mapd"));
  return released;
}

void MapServer::DropMap(const std::string& id, const Status& why) {
  MapHold map = maps_->Retire(id);
  if (map == nullptr) return;
  Log(LogLevel::kWarn, "map_dropped",
      {{"map", id},
       {"why", why.message()},
       {"action", "calls for it are redirected to its new owner; nothing acknowledged is lost"}});
  map->service->StartDraining();
  map->core->Stop(/*flush=*/false);  // the fence refuses what is queued; robots resend it
  if (auto* store = dynamic_cast<storage::PgStore*>(&map->core->store()); store != nullptr) {
    store->Close(Served(id, "taken over by another mapd"));
  }
  std::lock_guard<std::mutex> lock(health_mu_);
  server_->GetHealthCheckService()->SetServingStatus("map/" + id, false);
  UpdateHealthLocked();
}

StatusOr<std::unique_ptr<ServedMap>> MapServer::OpenPostgresMap(std::unique_ptr<ServedMap> map,
                                                                MapServiceImpl* shared_with,
                                                                const MapSettings* create_with) {
  const std::string& id = map->id;
  auto fail = [&](const Status& s) {
    return id == kDefaultMapId ? s : Status(s.code(), "map '" + id + "': " + s.message());
  };
  ServerConfig config = config_;
  if (create_with != nullptr) {
    // Checked first, then stored with the map's row: a refused setting leaves no map.
    if (Status s = ApplyMapSettings(*create_with, config_, &config); !s.ok()) return fail(s);
    // With a lease for this instance, so that no other takes the new map first.
    Status made = catalog_->CreateMap(id, MapSettingsText(*create_with), UnixNowNs(),
                                      &ownership_->instance(), config_.lease_ttl_s);
    if (made.code() == StatusCode::kAlreadyExists && IsArchived(id)) {
      return Status::AlreadyExists("map '" + id +
                                   "' is archived in the PostgreSQL database: restore it (mapctl "
                                   "maps restore " +
                                   id + ") or delete it for good (mapctl maps delete " + id +
                                   " --purge) first");
    }
    if (made.code() == StatusCode::kAlreadyExists) {
      return Status::AlreadyExists("map '" + id +
                                   "' is in the PostgreSQL database but not served here; restart "
                                   "mapd to serve it");
    }
    if (!made.ok()) return fail(made);
    map->settings = *create_with;
  } else {
    StatusOr<std::string> text = catalog_->Settings(id);
    if (text.ok()) {
      const std::string where = "the settings of map '" + id + "' in PostgreSQL";
      StatusOr<MapSettings> settings = ParseMapSettings(*text, where);
      if (!settings.ok()) return fail(settings.status());
      if (Status s = ApplyMapSettings(*settings, config_, &config); !s.ok()) {
        return fail(Status(s.code(), where + ": " + s.message()));
      }
      map->settings = *std::move(settings);
    } else if (text.status().code() != StatusCode::kNotFound || id != kDefaultMapId) {
      // NotFound: a new default map; any other map was archived or
      // deleted since the ownership round listed it.
      return fail(text.status());
    }
  }
  MapCoreOptions core_options = CoreOptions(config);
  core_options.postgres = config_.store;
  core_options.map_id = id;
  core_options.ownership.instance = ownership_->instance();
  core_options.ownership.lease_ttl_s = config_.lease_ttl_s;
  // A paused owner's open transaction holds a takeover back this long at most.
  core_options.ownership.idle_in_transaction_s = std::max(2 * config_.lease_ttl_s, 5.0);
  StatusOr<std::unique_ptr<MapCore>> core = MapCore::Open(core_options);
  if (!core.ok()) return fail(core.status());
  map->core = std::move(core).value();
  map->db_path = map->core->store().path();  // for the logs: "postgresql map <id>"
  map->service =
      std::make_unique<MapServiceImpl>(map->core.get(), config.ingest, config.submaps,
                                       config.streams, auth_, MapPlacement{id, shared_with});
  return map;
}

}  // namespace mapd::service
