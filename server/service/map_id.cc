#include "service/map_id.h"

#include "service/ingest_batch.h"

namespace mapd::service {

Status CheckMapId(const std::string& id, const std::string& what) {
  if (!ValidId(id) || id.front() == '.') {
    return Status::InvalidArgument(what + " '" + id.substr(0, 128) +
                                   "' is not a map id: 1-128 characters of [A-Za-z0-9_.-], "
                                   "not starting with '.'");
  }
  return Status::Ok();
}

std::vector<std::string> SplitMapIds(const std::string& joined) {
  std::vector<std::string> out;
  size_t start = 0;
  while (start < joined.size()) {
    size_t comma = joined.find(',', start);
    if (comma == std::string::npos) comma = joined.size();
    if (comma > start) out.push_back(joined.substr(start, comma - start));
    start = comma + 1;
  }
  return out;
}

std::string JoinMapIds(const std::vector<std::string>& ids) {
  std::string out;
  for (const std::string& id : ids) out += (out.empty() ? "" : ",") + id;
  return out;
}

}  // namespace mapd::service
