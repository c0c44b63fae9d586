// Map ids (docs/scale-out.md): what names a map in the API, on disk
// (<id>.db under --data-dir) and in a token's scope.
#ifndef MAPD_SERVICE_MAP_ID_H_
#define MAPD_SERVICE_MAP_ID_H_

#include <string>
#include <vector>

#include "common/status.h"

namespace mapd::service {

inline constexpr char kDefaultMapId[] = "default";

// A map id is a robot id (1-128 of [A-Za-z0-9_.-]) that does not start with
// '.' (it names a file). InvalidArgument naming `what` otherwise.
Status CheckMapId(const std::string& id, const std::string& what);

// "a,b" -> {"a", "b"}; "" -> {}.
std::vector<std::string> SplitMapIds(const std::string& joined);
std::string JoinMapIds(const std::vector<std::string>& ids);

}  // namespace mapd::service

#endif  // MAPD_SERVICE_MAP_ID_H_
