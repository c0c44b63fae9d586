// A 2D occupancy grid cut from a voxel map, written in the ROS map_server
// format (mapctl occupancy-grid): NAME.pgm (P5, 254 free, 0 occupied, 205
// unknown) and NAME.yaml (resolution, origin of the lower-left pixel, the
// trinary thresholds).
//
// A cell is occupied if any occupied voxel of the z band falls in it, free if
// only free voxels of the band do, else unknown. A voxel is in the band when
// its centre's z lies in [z_min, z_max].
#ifndef MAPD_CLIENT_OCCUPANCY_GRID_H_
#define MAPD_CLIENT_OCCUPANCY_GRID_H_

#include <cstdint>
#include <string>
#include <vector>

#include "common/status.h"
#include "voxel/voxel_grid.h"

namespace mapd::client {

enum class Cell : uint8_t { kUnknown, kFree, kOccupied };

struct OccupancyGridOptions {
  double z_min_m = 0.1;  // the band of heights that counts, map frame
  double z_max_m = 1.8;
  double resolution_m = 0;  // cell edge; 0 = the voxel map's resolution
  // A larger grid is refused (a far free leaf or a too fine resolution would
  // otherwise ask for gigabytes).
  int64_t max_cells = 100'000'000;
};

// A ground-plane segment in the map frame, metres (a fused wall).
struct GridLine {
  double ax = 0, ay = 0, bx = 0, by = 0;
};

struct OccupancyGrid {
  double resolution_m = 0;
  // The lower-left corner of the lower-left pixel (ROS `origin`), metres.
  double origin_x_m = 0, origin_y_m = 0;
  int width = 0, height = 0;
  // Row-major, row 0 the TOP of the map (largest y), as the image is stored.
  std::vector<Cell> cells;

  Cell at(int col, int row) const { return cells[static_cast<size_t>(row) * width + col]; }
  // The cell containing map point (x, y); false outside the grid.
  bool CellOf(double x, double y, int* col, int* row) const;
};

// The grid of the voxels of `voxels` in the band, grown to hold `lines`, which
// are drawn in as occupied. InvalidArgument for a bad band or resolution,
// FailedPrecondition when no voxel of the band is occupied, ResourceExhausted
// beyond options.max_cells.
StatusOr<OccupancyGrid> BuildOccupancyGrid(const voxel::VoxelGrid& voxels,
                                           const OccupancyGridOptions& options,
                                           const std::vector<GridLine>& lines = {});

// The image: binary PGM (P5), 254 free, 0 occupied, 205 unknown.
std::string EncodePgm(const OccupancyGrid& grid);
// The map_server YAML naming `image` (relative to the YAML's folder).
std::string EncodeMapYaml(const OccupancyGrid& grid, const std::string& image);

}  // namespace mapd::client

#endif  // MAPD_CLIENT_OCCUPANCY_GRID_H_
