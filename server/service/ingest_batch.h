// Validation of an incoming ObservationBatch and its conversion into the
// libraries' own types. Everything a robot sends passes through here first.
#ifndef MAPD_SERVICE_INGEST_BATCH_H_
#define MAPD_SERVICE_INGEST_BATCH_H_

#include <cstdint>
#include <string>

#include "common/status.h"
#include "geometry/observation.h"
#include "mapserver/v1/map_service.pb.h"
#include "storage/store.h"

namespace mapd::service {

// Limits on one batch. Over-limit batches are refused with RESOURCE_EXHAUSTED.
struct IngestLimits {
  uint32_t max_features_per_batch = 1024;  // lines + planes; at most kFeatureIdBits allow
  uint32_t max_boundary_points = 1024;     // per plane
  double max_abs_coordinate_m = 1e6;       // anything farther is a unit or frame error
  double quaternion_tolerance = 1e-3;      // accepted | |q| - 1 |
  uint32_t max_id_length = 128;            // robot_id, session_id

  Status Validate() const;
};

// Raw feature ids are (observation id << kFeatureIdBits) | index in the batch.
constexpr int kFeatureIdBits = 12;
constexpr uint32_t kMaxFeaturesPerBatchHard = 1u << kFeatureIdBits;

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
