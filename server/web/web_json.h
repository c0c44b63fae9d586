// The web view's JSON documents (nlohmann-json). Field names are the
// proto's (snake_case: map_version, member_count, z_min), so that a script
// written against `mapctl ... --json` or the gRPC API reads these too.
#ifndef MAPD_WEB_WEB_JSON_H_
#define MAPD_WEB_WEB_JSON_H_

#include <nlohmann/json.hpp>
#include <vector>

#include "service/core.h"
#include "service/watch_hub.h"
#include "storage/store.h"

namespace mapd::web {

using Json = nlohmann::ordered_json;

Json ToJson(const service::FusedView& v);
Json ToJson(const service::PlaneView& v);
// GET /api/features and an SSE resync event: the whole published map.
Json MapJson(uint64_t map_version, const std::vector<service::FusedView>& lines,
             const std::vector<service::PlaneView>& planes);
// An SSE change event: features and planes added or changed (their state as
// of to_version) and the ids no longer published.
Json ChangeJson(const service::MapChange& change);
Json ToJson(const storage::MergeRecord& r);
// Text with invalid UTF-8 replaced (robot names are checked, reasons are
// free text).
std::string Dump(const Json& j);

}  // namespace mapd::web

#endif  // MAPD_WEB_WEB_JSON_H_
