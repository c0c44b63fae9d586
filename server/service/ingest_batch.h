// Validation of an incoming ObservationBatch and its conversion into the
// libraries' own types. Everything a robot sends passes through here first.
#ifndef MAPD_SERVICE_INGEST_BATCH_H_
#define MAPD_SERVICE_INGEST_BATCH_H_

#include <cstdint>
#include <string>

#include "common/status.h"
#include "geometry/observation.h"
#include "mapserver/v1/map_service.pb.h"
#include "service/options.h"
#include "storage/store.h"

namespace mapd::service {

// A robot or session id of the API: 1 to max_length characters of
// [A-Za-z0-9_.-] (ingest, submap uploads, tokens' robot scope).
bool ValidId(const std::string& id, uint32_t max_length = IngestLimits{}.max_id_length);

// A validated batch in library types.
struct IngestBatch {
  std::string robot;
  std::string session;
  uint64_t seq = 0;
  int64_t stamp_ns = 0;
  storage::FrameKind frame_kind = storage::FrameKind::kMap;
  geometry::SensorObservation features;  // normalised quaternion and plane normals
};

// Checks every field and converts. The error names the first offending field,
// e.g. "lines[3].a.x is NaN" (INVALID_ARGUMENT) or "batch has 5000 features;
// the limit is 1024" (RESOURCE_EXHAUSTED).
StatusOr<IngestBatch> ValidateBatch(const mapserver::v1::ObservationBatch& in,
                                    const IngestLimits& limits);

}  // namespace mapd::service

#endif  // MAPD_SERVICE_INGEST_BATCH_H_
