// Where the maps of a shared database are served, for the router
// (map_router.h): redirects, ListMaps and LocateMap. MapOwnership
// (map_ownership.h) is the implementation; with a local store there is none.
#ifndef MAPD_SERVICE_MAP_LOCATOR_H_
#define MAPD_SERVICE_MAP_LOCATOR_H_

#include <map>
#include <optional>
#include <string>

namespace mapd::service {

// The instance serving a map.
struct MapOwner {
  std::string instance;
  std::string address;  // host:port; empty while nobody has taken the map
  bool live = false;    // its lease runs; false: being taken over
};

class MapLocator {
 public:
  virtual ~MapLocator() = default;
  // Map `id`'s owner as last seen; nullopt when the database has no such map.
  virtual std::optional<MapOwner> Locate(const std::string& id) const = 0;
  // The same read from the database now, for a map last seen without a live
  // owner (being taken over: the takeover may have happened since) or not
  // seen at all (made since on another instance). As last seen when the
  // database cannot be reached.
  virtual std::optional<MapOwner> LocateNow(const std::string& id) = 0;
  // Every map of the database and its owner, read now (as last seen when
  // the database cannot be reached).
  virtual std::map<std::string, MapOwner> Owners() = 0;
  // How soon a map being taken over is worth asking for again: the view is
  // refreshed this often, milliseconds.
  virtual int retry_after_ms() const = 0;
};

}  // namespace mapd::service

#endif  // MAPD_SERVICE_MAP_LOCATOR_H_
