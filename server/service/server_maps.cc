// MapServer's side of a map's life beyond CreateMap (map_lifecycle.h):
// archiving, deleting and restoring maps, on a --data-dir (files moved to
// DIR/archive/, map_archive.h) or a shared PostgreSQL database (rows kept
// and flagged, the lease held by nobody: PgMapCatalog::ArchiveMap).
#include <chrono>
#include <thread>

#include "common/clock.h"
#include "service/log.h"
#include "service/server.h"
#include "storage/postgres/store.h"

namespace mapd::service {
namespace {

// How long an archive on a --data-dir waits for calls still holding the
// map (a read in progress) before it moves the files anyway: they stay
// readable through the open descriptors, and the map is freed later.
constexpr auto kHoldersWait = std::chrono::seconds(5);

}  // namespace

StatusOr<std::string> MapServer::DeleteMap(const std::string& id, bool purge) {
  if (id == kDefaultMapId) {
    return Status::FailedPrecondition(
        "the default map cannot be deleted: it holds the server's tokens and audit log, and "
        "clients that name no map write into it");
  }
  if (!maps_->can_create()) {
    return Status::FailedPrecondition(
        "this mapd serves one database (--db); stop it and move the file away instead, or "
        "serve maps from a --data-dir");
  }
  std::lock_guard<std::mutex> lock(lifecycle_mu_);
  // Its lease stays this instance's until archived: no round may reopen it.
  if (ownership_ != nullptr) ownership_->MarkLeaving(id, true);
  MapHold map = maps_->Retire(id);
  const bool served = map != nullptr;
  StatusOr<std::string> where = served ? Archive(id, std::move(map)) : std::string();
  if (ownership_ != nullptr) ownership_->MarkLeaving(id, false);
  if (served && (!where.ok() || !purge)) return where;
  if (!served && !IsArchived(id)) {
    return Status::NotFound("map '" + id +
                            "' is neither served here nor archived; ListMaps (mapctl maps) "
                            "names the maps");
  }
  if (!served && !purge) {
    return Status::FailedPrecondition("map '" + id +
                                      "' is archived already; purge deletes it for good "
                                      "(mapctl maps delete " +
                                      id + " --purge), RestoreMap serves it again");
  }
  MAPD_RETURN_IF_ERROR(Purge(id));
  Log(LogLevel::kInfo, "map_purged", {{"map", id}});
  return std::string();
}

StatusOr<std::string> MapServer::Archive(const std::string& id, MapHold map) {
  Log(LogLevel::kInfo, "map_archiving", {{"map", id}});
  map->service->StartDraining();  // streams end UNAVAILABLE once their batches are acknowledged
  map->core->Stop();              // commits what is queued, writes a snapshot
  {
    std::lock_guard<std::mutex> lock(health_mu_);
    server_->GetHealthCheckService()->SetServingStatus("map/" + id, false);
    UpdateHealthLocked();
  }
  if (maps_->postgres()) {
    auto* store = dynamic_cast<storage::PgStore*>(&map->core->store());
    Status archived = store != nullptr
                          ? catalog_->ArchiveMap(store->lease(), UnixNowNs())
                          : Status::Internal("map '" + id + "' has no PostgreSQL store");
    if (store != nullptr) {
      // Without the archive the lease lapses (nobody renews it) and an
      // instance takes the map again: nothing is lost either way.
      if (!archived.ok()) (void)store->ReleaseLease();
      store->Close(Status::NotFound("map '" + id + "' was deleted (archived)"));
    }
    ownership_->Forget(id);
    if (!archived.ok()) {
      return Status(archived.code(), "map '" + id + "' was not archived: " + archived.message() +
                                         "; it is served again once an instance takes it");
    }
    Log(LogLevel::kInfo, "map_archived", {{"map", id}, {"where", "postgresql"}});
    return std::string("postgresql");
  }
  // A file: its connections and lock go with the map, once no call holds it.
  const auto deadline = std::chrono::steady_clock::now() + kHoldersWait;
  while (map.use_count() > 2 && std::chrono::steady_clock::now() < deadline) {  // here and retired
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  map.reset();
  maps_->Reap();
  if (Status moved = ArchiveMapFiles(config_.data_dir, id); !moved.ok()) {
    // Serve it again rather than leave it half gone.
    StatusOr<MapHold> back = maps_->Reopen(id);
    if (back.ok()) WatchMap(back->get());
    return Status(moved.code(),
                  "map '" + id + "' was not archived: " + moved.message() +
                      (back.ok() ? "; it is served again"
                                 : "; it could not be served again: " + back.status().message()));
  }
  const std::string where = ArchivedMapPath(config_.data_dir, id);
  Log(LogLevel::kInfo, "map_archived", {{"map", id}, {"where", where}});
  return where;
}

Status MapServer::Purge(const std::string& id) {
  if (maps_->postgres()) return catalog_->PurgeArchived(id);
  return PurgeArchivedFiles(config_.data_dir, id);
}

bool MapServer::IsArchived(const std::string& id) {
  if (!maps_->postgres()) return service::IsArchived(config_.data_dir, id);
  StatusOr<std::vector<storage::PgMapCatalog::Archived>> archived = catalog_->ListArchived();
  if (!archived.ok()) return false;
  for (const auto& a : *archived) {
    if (a.id == id) return true;
  }
  return false;
}

StatusOr<MapHold> MapServer::RestoreMap(const std::string& id) {
  if (!maps_->can_create()) {
    return Status::FailedPrecondition("this mapd serves one database (--db); it has no archive");
  }
  std::lock_guard<std::mutex> lock(lifecycle_mu_);
  if (maps_->Find(id).ok()) {
    return Status::AlreadyExists("map '" + id + "' is served here; it is not archived");
  }
  if (maps_->postgres()) {
    MAPD_RETURN_IF_ERROR(catalog_->RestoreMap(id));
    Log(LogLevel::kInfo, "map_restored", {{"map", id}, {"from", "postgresql"}});
    // Served here at once; the ownership rounds may hand it on later. If
    // another instance's round took it first, it is served there.
    if (Status taken = TakeMap(id); !taken.ok()) {
      // A round here may have opened it meanwhile (AlreadyExists).
      if (StatusOr<MapHold> here = maps_->Find(id); here.ok()) return here;
      Log(LogLevel::kInfo, "map_not_taken", {{"map", id}, {"why", taken.ToString()}});
      return MapHold();
    }
    return maps_->Find(id);
  }
  MAPD_RETURN_IF_ERROR(RestoreMapFiles(config_.data_dir, id));
  StatusOr<MapHold> map = maps_->Reopen(id);
  if (!map.ok()) {
    // Back into the archive: a map that cannot be served must not stop the next start.
    Status back = ArchiveMapFiles(config_.data_dir, id);
    return Status(
        map.status().code(),
        "map '" + id + "' cannot be served: " + map.status().message() +
            (back.ok() ? "; it stays archived" : "; its files are back in the directory"));
  }
  WatchMap(map->get());
  Log(LogLevel::kInfo, "map_restored", {{"map", id}, {"from", config_.data_dir}});
  return map;
}

StatusOr<std::vector<ArchivedMap>> MapServer::ListArchived() {
  if (!maps_->postgres()) {
    if (config_.data_dir.empty()) return std::vector<ArchivedMap>();
    return ListArchivedFiles(config_.data_dir);
  }
  StatusOr<std::vector<storage::PgMapCatalog::Archived>> rows = catalog_->ListArchived();
  if (!rows.ok()) return rows.status();
  std::vector<ArchivedMap> out;
  for (const auto& r : *rows) out.push_back({r.id, r.archived_ns});
  return out;
}

}  // namespace mapd::service
