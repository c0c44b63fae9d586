// libFuzzer target: what mapd does with the bytes of one Ingest message before
// anything is stored: protobuf parsing, then ValidateBatch with the default
// limits (as IngestReactor runs it on every batch), then the storage encoding
// of an accepted batch. The same bytes are also fed to the storage decoder as
// a damaged database payload.
// Beyond crashes and sanitizer reports, a bug is: an accepted batch with
// non-finite or out-of-limit values, or one whose stored encoding does not
// decode to exactly what was accepted.
#include <google/protobuf/stubs/logging.h>

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string>
#include <string_view>

#include "mapserver/v1/map_service.pb.h"
#include "service/ingest_batch.h"
#include "storage/observation_codec.h"

namespace {

using mapd::geometry::SensorObservation;

void Check(bool ok) {
  if (!ok) std::abort();
}

bool Finite(const Eigen::Vector3d& v, double max_abs) {
  return v.allFinite() && v.cwiseAbs().maxCoeff() <= max_abs;
}

void CheckAccepted(const mapd::service::IngestBatch& b, const mapd::service::IngestLimits& limits) {
  const SensorObservation& f = b.features;
  Check(!b.robot.empty() && b.robot.size() <= limits.max_id_length);
  Check(!b.session.empty() && b.session.size() <= limits.max_id_length);
  Check(b.seq >= 1);
  Check(f.lines.size() + f.planes.size() <= limits.max_features_per_batch);
  Check(std::abs(f.T_frame_sensor.rotation.norm() - 1.0) < 1e-9);
  for (const auto& l : f.lines) {
    Check(Finite(l.a, limits.max_abs_coordinate_m) && Finite(l.b, limits.max_abs_coordinate_m));
  }
  for (const auto& p : f.planes) {
    Check(p.normal.allFinite() && std::abs(p.normal.norm() - 1.0) < 1e-9);
    Check(std::isfinite(p.offset) && p.boundary.size() >= 3 &&
          p.boundary.size() <= limits.max_boundary_points);
    for (const auto& v : p.boundary) Check(Finite(v, limits.max_abs_coordinate_m));
  }

  std::string payload;
  mapd::storage::EncodeFeatures(f, &payload);
  SensorObservation decoded;
  Check(mapd::storage::DecodeFeatures(payload, &decoded).ok());
  Check(decoded.lines.size() == f.lines.size() && decoded.planes.size() == f.planes.size());
  for (size_t i = 0; i < f.lines.size(); ++i) {
    Check(decoded.lines[i].a == f.lines[i].a && decoded.lines[i].b == f.lines[i].b);
  }
  for (size_t i = 0; i < f.planes.size(); ++i) {
    Check(decoded.planes[i].normal == f.planes[i].normal &&
          decoded.planes[i].offset == f.planes[i].offset &&
          decoded.planes[i].boundary == f.planes[i].boundary);
  }
}

}  // namespace

// Protobuf logs every string field with invalid UTF-8 to stderr (gRPC refuses
// such a message too); silenced, so the fuzzer does not spend its time writing.
extern "C" int LLVMFuzzerInitialize(int*, char***) {
  google::protobuf::SetLogHandler(nullptr);
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  // A damaged database row must be refused, never read past its end.
  SensorObservation scratch;
  (void)mapd::storage::DecodeFeatures(std::string_view(reinterpret_cast<const char*>(data), size),
                                      &scratch);

  mapserver::v1::ObservationBatch batch;
  if (!batch.ParseFromArray(data, static_cast<int>(size))) return 0;  // gRPC refuses it first
  const mapd::service::IngestLimits limits;                           // mapd's defaults
  mapd::StatusOr<mapd::service::IngestBatch> accepted = mapd::service::ValidateBatch(batch, limits);
  if (accepted.ok()) {
    CheckAccepted(*accepted, limits);
  } else {
    Check(!accepted.status().message().empty());  // the client is told which field
  }
  return 0;
}
