#include "client/occupancy_grid.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

namespace mapd::client {
namespace {

// Tolerance in cells for box edges that sit on cell edges up to rounding.
constexpr double kEdgeEps = 1e-6;

std::string Num(double v) {
  char buf[64];
  std::snprintf(buf, sizeof(buf), "%.9g", v);
  return buf;
}

// An axis-aligned ground-plane box, metres: [x0, x1) x [y0, y1).
struct Box2 {
  double x0, y0, x1, y1;
};

struct Extent {
  double x0 = std::numeric_limits<double>::infinity(), y0 = x0;
  double x1 = -std::numeric_limits<double>::infinity(), y1 = x1;
  void Add(double x, double y) {
    x0 = std::min(x0, x);
    y0 = std::min(y0, y);
    x1 = std::max(x1, x);
    y1 = std::max(y1, y);
  }
};

void Fill(const Box2& b, Cell value, OccupancyGrid* g) {
  const double r = g->resolution_m;
  const int c0 = std::max(0, static_cast<int>(std::floor((b.x0 - g->origin_x_m) / r + kEdgeEps)));
  const int c1 = std::min(g->width - 1,
                          static_cast<int>(std::ceil((b.x1 - g->origin_x_m) / r - kEdgeEps)) - 1);
  // From the bottom: image row = height - 1 - up.
  const int u0 = std::max(0, static_cast<int>(std::floor((b.y0 - g->origin_y_m) / r + kEdgeEps)));
  const int u1 = std::min(g->height - 1,
                          static_cast<int>(std::ceil((b.y1 - g->origin_y_m) / r - kEdgeEps)) - 1);
  for (int u = u0; u <= u1; ++u) {
    Cell* row = &g->cells[static_cast<size_t>(g->height - 1 - u) * g->width];
    for (int c = c0; c <= c1; ++c) {
      if (value == Cell::kOccupied || row[c] == Cell::kUnknown) row[c] = value;
    }
  }
}

void DrawLine(const GridLine& line, OccupancyGrid* g) {
  // Samples a quarter cell apart: every cell the segment crosses gets one.
  const double length = std::hypot(line.bx - line.ax, line.by - line.ay);
  if (!std::isfinite(length)) return;  // the server never serves such a wall
  const int steps = static_cast<int>(std::ceil(length / (g->resolution_m / 4))) + 1;
  for (int i = 0; i <= steps; ++i) {
    const double t = static_cast<double>(i) / steps;
    int col = 0, row = 0;
    if (g->CellOf(line.ax + t * (line.bx - line.ax), line.ay + t * (line.by - line.ay), &col,
                  &row)) {
      g->cells[static_cast<size_t>(row) * g->width + col] = Cell::kOccupied;
    }
  }
}

}  // namespace

bool OccupancyGrid::CellOf(double x, double y, int* col, int* row) const {
  const double c = std::floor((x - origin_x_m) / resolution_m);
  const double u = std::floor((y - origin_y_m) / resolution_m);
  if (!(c >= 0 && c < width && u >= 0 && u < height)) return false;
  *col = static_cast<int>(c);
  *row = height - 1 - static_cast<int>(u);
  return true;
}

StatusOr<OccupancyGrid> BuildOccupancyGrid(const voxel::VoxelGrid& voxels,
                                           const OccupancyGridOptions& options,
                                           const std::vector<GridLine>& lines) {
  const double zlo = options.z_min_m, zhi = options.z_max_m;
  if (!std::isfinite(zlo) || !std::isfinite(zhi) || zlo >= zhi) {
    return Status::InvalidArgument("bad z band: --z-min (" + Num(zlo) +
                                   " m) must be finite and below --z-max (" + Num(zhi) + " m)");
  }
  const double res = voxels.resolution();
  const double r = options.resolution_m == 0 ? res : options.resolution_m;
  if (!std::isfinite(r) || r <= 0 || r > 1000) {
    return Status::InvalidArgument("bad --resolution " + Num(r) +
                                   ": a cell edge in metres, > 0 and at most 1000");
  }
  // Voxel layers whose centres lie in [zlo, zhi].
  const int kz_min = static_cast<int>(std::ceil(zlo / res - 0.5));
  const int kz_max = static_cast<int>(std::floor(zhi / res - 0.5));
  if (kz_min > kz_max) {
    return Status::InvalidArgument("the z band [" + Num(zlo) + ", " + Num(zhi) +
                                   "] m holds no voxel centre at the map's resolution " + Num(res) +
                                   " m: widen it");
  }

  std::vector<Box2> occupied, free;
  Extent extent;
  double z_lowest = std::numeric_limits<double>::infinity(), z_highest = -z_lowest;
  for (const voxel::VoxelKey& k : voxels.occupied_keys()) {
    z_lowest = std::min(z_lowest, k.z() * res);
    z_highest = std::max(z_highest, (k.z() + 1) * res);
    if (k.z() < kz_min || k.z() > kz_max) continue;
    const Box2 b{k.x() * res, k.y() * res, (k.x() + 1) * res, (k.y() + 1) * res};
    occupied.push_back(b);
    extent.Add(b.x0, b.y0);
    extent.Add(b.x1, b.y1);
  }
  if (occupied.empty()) {
    if (voxels.empty()) return Status::FailedPrecondition("the voxel map has no occupied voxel");
    return Status::FailedPrecondition("no occupied voxel between z " + Num(zlo) + " and " +
                                      Num(zhi) + " m (the map's occupied voxels span z " +
                                      Num(z_lowest) + " to " + Num(z_highest) +
                                      " m): choose another --z-min/--z-max");
  }
  voxels.ForEachFreeCube([&](const voxel::VoxelKey& k, int edge) {
    if (k.z() + edge - 1 < kz_min || k.z() > kz_max) return;
    const Box2 b{k.x() * res, k.y() * res, (k.x() + edge) * res, (k.y() + edge) * res};
    free.push_back(b);
    extent.Add(b.x0, b.y0);
    extent.Add(b.x1, b.y1);
  });
  for (const GridLine& l : lines) {
    extent.Add(l.ax, l.ay);
    extent.Add(l.bx, l.by);
  }

  OccupancyGrid g;
  g.resolution_m = r;
  g.origin_x_m = std::floor(extent.x0 / r + kEdgeEps) * r;
  g.origin_y_m = std::floor(extent.y0 / r + kEdgeEps) * r;
  const double w = std::max(1.0, std::ceil((extent.x1 - g.origin_x_m) / r - kEdgeEps));
  const double h = std::max(1.0, std::ceil((extent.y1 - g.origin_y_m) / r - kEdgeEps));
  if (w * h > static_cast<double>(options.max_cells)) {
    return Status::ResourceExhausted("the grid would be " + Num(w) + " x " + Num(h) + " cells of " +
                                     Num(r) + " m (more than " + std::to_string(options.max_cells) +
                                     "): use a coarser --resolution");
  }
  g.width = static_cast<int>(w);
  g.height = static_cast<int>(h);
  g.cells.assign(static_cast<size_t>(g.width) * g.height, Cell::kUnknown);
  for (const Box2& b : free) Fill(b, Cell::kFree, &g);
  for (const Box2& b : occupied) Fill(b, Cell::kOccupied, &g);
  for (const GridLine& l : lines) DrawLine(l, &g);
  return g;
}

std::string EncodePgm(const OccupancyGrid& grid) {
  std::string out =
      "P5\n" + std::to_string(grid.width) + " " + std::to_string(grid.height) + "\n255\n";
  out.reserve(out.size() + grid.cells.size());
  for (Cell c : grid.cells) {
    out.push_back(static_cast<char>(c == Cell::kOccupied ? 0 : c == Cell::kFree ? 254 : 205));
  }
  return out;
}

std::string EncodeMapYaml(const OccupancyGrid& grid, const std::string& image) {
  return "image: " + image + "\nmode: trinary\nresolution: " + Num(grid.resolution_m) +
         "\norigin: [" + Num(grid.origin_x_m) + ", " + Num(grid.origin_y_m) +
         ", 0.0]\nnegate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.196\n";
}

}  // namespace mapd::client
