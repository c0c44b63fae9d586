// GET /metrics: mapd's figures in the Prometheus text format (0.0.4).
#ifndef MAPD_WEB_METRICS_H_
#define MAPD_WEB_METRICS_H_

#include <string>

#include "service/core.h"

namespace mapd::web {

// Reads the core's stats, the store's size and merges, and the watchers:
// cheap (no map query), so a scrape every few seconds costs nothing.
std::string MetricsText(service::Core& core);

}  // namespace mapd::web

#endif  // MAPD_WEB_METRICS_H_
