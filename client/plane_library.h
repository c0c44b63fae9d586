// The robot library's plane extractor for mapctl, loaded when a folder of 3D
// scans is replayed: libmapd_robot_c.so (client/robot/c_api.h), the same
// library Python's mapd_client.planes loads. mapctl itself links no PCL, so
// it runs where PCL is not installed (the container's runtime image); the
// folders replay where the library is.
#ifndef MAPD_CLIENT_PLANE_LIBRARY_H_
#define MAPD_CLIENT_PLANE_LIBRARY_H_

#include <memory>
#include <string>
#include <vector>

#include "common/status.h"
#include "geometry/observation.h"

namespace mapd::client {

class PlaneLibrary {
 public:
  // Loads the library from, in order: $MAPD_ROBOT_LIBRARY; lib/ beside the
  // directory of mapctl (an install: bin/mapctl, lib/libmapd_robot_c.so);
  // robot/ beside mapctl (the build tree); the system's library path.
  // NotFound saying where it looked and how to get it.
  static StatusOr<std::unique_ptr<PlaneLibrary>> Load();
  ~PlaneLibrary();
  PlaneLibrary(const PlaneLibrary&) = delete;
  PlaneLibrary& operator=(const PlaneLibrary&) = delete;

  // The planes of the scan in `path` (a .pcd, .ply, .bin or .xyz file), in
  // the sensor frame, with the default PlaneExtractionParams; organised
  // scans as organised (wrap_columns for a 360 degree LiDAR). The library's
  // Status (NotFound, InvalidArgument naming the file) on failure.
  StatusOr<std::vector<geometry::PlaneFeature>> PlanesOfFile(const std::string& path,
                                                             bool wrap_columns) const;

  const std::string& path() const { return path_; }

 private:
  struct Api;
  PlaneLibrary(void* handle, std::string path, std::unique_ptr<Api> api);
  void* handle_;
  std::string path_;
  std::unique_ptr<Api> api_;
};

}  // namespace mapd::client

#endif  // MAPD_CLIENT_PLANE_LIBRARY_H_
