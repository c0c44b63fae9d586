// Point cloud files, for replaying recorded 3D scans (mapctl replay) and for
// robots that log them: PCD (ascii, binary, binary_compressed) and PLY (its
// vertices) through PCL's readers, KITTI's Velodyne .bin (float32 x y z
// reflectance), and plain text with one "x y z" a line (.xyz, .txt, .dat:
// OctoMap's scan.dat, many scanners' exports). Only x y z are read; metres,
// in the sensor frame.
#ifndef MAPD_CLIENT_ROBOT_CLOUD_FILES_H_
#define MAPD_CLIENT_ROBOT_CLOUD_FILES_H_

#include <Eigen/Core>
#include <string>
#include <vector>

#include "client/robot/cloud_planes.h"
#include "common/status.h"

namespace mapd::robot {

struct CloudFile {
  std::vector<Eigen::Vector3f> points;  // row-major when organised
  int rows = 1;                         // a PCD's height: > 1 is an organised scan
  int columns = 0;                      // its width
  bool organised() const { return rows > 1; }
  // The scan as ExtractPlanes takes it; wrap_columns for a 360 degree LiDAR.
  OrganisedCloud AsOrganised(bool wrap_columns) const;
};

// The cloud in `path`, its format from the extension (.pcd, .ply, .bin; .xyz,
// .txt, .dat for text). NotFound if it cannot be opened; InvalidArgument
// naming the file (and the line, for text) if it is not a cloud of that
// format or has no x y z; an empty cloud is a cloud.
StatusOr<CloudFile> ReadCloudFile(const std::string& path);

// The planes of a file's cloud: organised or not, as it is.
StatusOr<std::vector<ExtractedPlane>> ExtractPlanes(const CloudFile& cloud, bool wrap_columns,
                                                    const PlaneExtractionParams& params,
                                                    PlaneExtractionStats* stats = nullptr);

}  // namespace mapd::robot

#endif  // MAPD_CLIENT_ROBOT_CLOUD_FILES_H_
