// The ObservationBatch a robot sends for one scan (mapserver.v1, see
// RobotClient): who and when, where the sensor was, and the scan's lines in
// the sensor frame. What the server would refuse for its form (a pose that
// is not a rigid transform, a sequence number of 0, missing ids) is refused
// here first, with the field named, so a robot finds its bug before it
// streams.
#ifndef MAPD_CLIENT_ROBOT_OBSERVATION_BATCH_H_
#define MAPD_CLIENT_ROBOT_OBSERVATION_BATCH_H_

#include <Eigen/Geometry>
#include <cstdint>
#include <string>
#include <vector>

#include "client/robot/laser_lines.h"
#include "common/status.h"
#include "geometry/observation.h"
#include "mapserver/v1/map_service.pb.h"

namespace mapd::robot {

struct BatchHeader {
  std::string robot_id;    // required; the server checks its alphabet
  std::string session_id;  // required; one frame per (robot, session)
  uint64_t seq = 0;        // >= 1, unique within the session
  int64_t stamp_ns = 0;    // acquisition time, ns since the Unix epoch; passed through
  // MAP: the poses are in the map frame (a localised robot). LOCAL: in the
  // robot's own frame, fused once a submap merge ties it to the map.
  mapserver::v1::SessionFrame frame = mapserver::v1::SESSION_FRAME_MAP;
};

// A batch of `lines` (sensor frame, z = 0) seen from `T_frame_sensor` (the
// sensor's pose in the session frame, metres). InvalidArgument naming the
// field for an empty robot or session id, seq 0, a pose that is not finite
// or whose rotation is not orthonormal (within 1e-6), and a line that is
// not finite or has no length.
StatusOr<mapserver::v1::ObservationBatch> LineBatch(const BatchHeader& header,
                                                    const Eigen::Isometry3d& T_frame_sensor,
                                                    const std::vector<ExtractedLine>& lines);

// A batch of lines and planes (sensor frame: a 3D scan's planes from
// cloud_planes.h). As LineBatch, and InvalidArgument naming the plane whose
// normal is not unit (within 1e-3), offset not finite, or boundary not 3 or
// more finite points.
StatusOr<mapserver::v1::ObservationBatch> FeatureBatch(
    const BatchHeader& header, const Eigen::Isometry3d& T_frame_sensor,
    const std::vector<ExtractedLine>& lines, const std::vector<geometry::PlaneFeature>& planes);

// ExtractLines and LineBatch in one: the batch for one scan.
StatusOr<mapserver::v1::ObservationBatch> ScanBatch(const BatchHeader& header,
                                                    const Eigen::Isometry3d& T_frame_sensor,
                                                    const LaserScan& scan,
                                                    const LineExtractionParams& params);

}  // namespace mapd::robot

#endif  // MAPD_CLIENT_ROBOT_OBSERVATION_BATCH_H_
