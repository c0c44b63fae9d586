// The binary payload of a stored observation: its lines and planes, in the
// sensor frame, exactly as the robot sent them. Little-endian, versioned:
//   u32 version (=1) | u32 n_lines | n_lines * 6 f64 (a.xyz, b.xyz)
//   | u32 n_planes | per plane: 4 f64 (normal.xyz, offset), u32 n, n * 3 f64
#ifndef MAPD_STORAGE_OBSERVATION_CODEC_H_
#define MAPD_STORAGE_OBSERVATION_CODEC_H_

#include <string>
#include <string_view>

#include "common/status.h"
#include "geometry/observation.h"

namespace mapd::storage {

// Appends the encoding of obs.lines and obs.planes to *out (the pose is stored in columns).
void EncodeFeatures(const geometry::SensorObservation& obs, std::string* out);
// Decodes into obs->lines / obs->planes. A truncated or inconsistent payload is
// refused with Internal (the database is damaged), never read past its end.
Status DecodeFeatures(std::string_view payload, geometry::SensorObservation* obs);

}  // namespace mapd::storage

#endif  // MAPD_STORAGE_OBSERVATION_CODEC_H_
