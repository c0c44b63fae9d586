// RenderTopView: the map area of a voxel rendering. Each layer keeps its own
// highest voxel per pixel so that two coinciding layers can both be shown
// (their shaded colours are averaged) instead of the last one hiding the rest.
#include "client/voxel_render.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <limits>

namespace mapd::client {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
// Pixel boundaries are nudged by this many pixels so that a voxel face lying
// exactly on a pixel edge covers one pixel, not two.
constexpr double kEdgeEps = 1e-6;

bool IsFinite(const Eigen::Vector3d& p) {
  return std::isfinite(p.x()) && std::isfinite(p.y()) && std::isfinite(p.z());
}

// Darkest shade at the lowest voxel: floors stay visible but walls stand out.
constexpr double kMinBrightness = 0.35;

Rgb Shade(Rgb c, double brightness) {
  auto f = [brightness](uint8_t v) { return static_cast<double>(v) * brightness; };
  return {static_cast<uint8_t>(std::lround(f(c.r))), static_cast<uint8_t>(std::lround(f(c.g))),
          static_cast<uint8_t>(std::lround(f(c.b)))};
}

}  // namespace

Rgb LayerColour(size_t index) {
  // Colour-blind friendly first (Okabe-Ito), saturated enough to shade.
  static const Rgb kColours[] = {{213, 94, 0},  {0, 114, 178},  {0, 158, 115},  {204, 121, 167},
                                 {230, 159, 0}, {86, 180, 233}, {120, 60, 200}, {160, 160, 40}};
  return kColours[index % (sizeof(kColours) / sizeof(kColours[0]))];
}

Status RenderOptions::Validate() const {
  if (!std::isfinite(pixel_m) || pixel_m < 0)
    return Status::InvalidArgument("pixel_m must be finite and >= 0 metres");
  if (max_map_px < 16 || max_map_px > 16384)
    return Status::InvalidArgument("max_map_px must be in [16, 16384]");
  if (min_map_px < 1 || min_map_px > max_map_px) {
    return Status::InvalidArgument("min_map_px must be in [1, max_map_px]");
  }
  if (margin_px < 0 || margin_px > 1000)
    return Status::InvalidArgument("margin_px must be in [0, 1000]");
  if (text_scale < 1 || text_scale > 8)
    return Status::InvalidArgument("text_scale must be in [1, 8]");
  return Status::Ok();
}

void TopView::MetresToPixel(double x, double y, int* col, int* row) const {
  *col = static_cast<int>(std::floor((x - x_min_m) / pixel_m));
  *row = static_cast<int>(std::floor((y_max_m - y) / pixel_m));
}

StatusOr<TopView> RenderTopView(const std::vector<VoxelLayer>& layers,
                                const RenderOptions& options) {
  MAPD_RETURN_IF_ERROR(options.Validate());
  if (layers.empty()) return Status::InvalidArgument("layers is empty: nothing to render");

  // Transform every layer once; bounds are those of the voxels' squares.
  std::vector<std::vector<Eigen::Vector3d>> points(layers.size());
  double x_min = kInf, x_max = -kInf, y_min = kInf, y_max = -kInf, z_min = kInf, z_max = -kInf;
  double finest = kInf;
  for (size_t i = 0; i < layers.size(); ++i) {
    const VoxelLayer& layer = layers[i];
    if (!std::isfinite(layer.resolution_m) || layer.resolution_m <= 0) {
      return Status::InvalidArgument("layers[" + std::to_string(i) +
                                     "].resolution_m must be finite and > 0");
    }
    const double half = layer.resolution_m / 2;
    points[i].reserve(layer.centres_m.size());
    for (const Eigen::Vector3d& c : layer.centres_m) {
      const Eigen::Vector3d p = layer.T_view_layer * c;
      if (!IsFinite(p)) {
        return Status::InvalidArgument("layers[" + std::to_string(i) + "] (" + layer.label +
                                       ") has a point that is not finite after its transform");
      }
      points[i].push_back(p);
      x_min = std::min(x_min, p.x() - half), x_max = std::max(x_max, p.x() + half);
      y_min = std::min(y_min, p.y() - half), y_max = std::max(y_max, p.y() + half);
      z_min = std::min(z_min, p.z()), z_max = std::max(z_max, p.z());
    }
    if (!layer.centres_m.empty()) finest = std::min(finest, layer.resolution_m);
  }
  if (!(x_min <= x_max))
    return Status::InvalidArgument("no occupied voxel in any layer: nothing to render");

  TopView view;
  const double extent = std::max(x_max - x_min, y_max - y_min);
  double pixel_m = options.pixel_m;
  if (pixel_m == 0) pixel_m = std::min(finest, extent / options.min_map_px);
  view.pixel_m = std::max(pixel_m, extent / options.max_map_px);
  view.x_min_m = x_min;
  view.y_max_m = y_max;
  const int width =
      std::max(1, static_cast<int>(std::ceil((x_max - x_min) / view.pixel_m - kEdgeEps)));
  const int height =
      std::max(1, static_cast<int>(std::ceil((y_max - y_min) / view.pixel_m - kEdgeEps)));
  view.x_max_m = x_min + width * view.pixel_m;
  view.y_min_m = y_max - height * view.pixel_m;
  // Shading range: the 1st to 99th percentile of the heights, so that a few
  // stray voxels high above (a tree, a ceiling lamp, sensor noise) do not
  // squeeze every wall into the darkest shades.
  {
    std::vector<double> zs;
    for (const std::vector<Eigen::Vector3d>& layer : points) {
      for (const Eigen::Vector3d& p : layer) zs.push_back(p.z());
    }
    const size_t lo = static_cast<size_t>(std::floor(0.01 * static_cast<double>(zs.size() - 1)));
    const size_t hi = static_cast<size_t>(std::ceil(0.99 * static_cast<double>(zs.size() - 1)));
    std::nth_element(zs.begin(), zs.begin() + static_cast<long>(lo), zs.end());
    z_min = zs[lo];
    std::nth_element(zs.begin(), zs.begin() + static_cast<long>(hi), zs.end());
    z_max = zs[hi];
  }
  view.z_min_m = z_min;
  view.z_max_m = z_max;
  view.map = RgbImage(width, height, options.background);

  // Highest voxel per pixel and layer (-inf: none).
  const size_t num_pixels = static_cast<size_t>(width) * static_cast<size_t>(height);
  std::vector<std::vector<float>> top(layers.size());
  for (size_t i = 0; i < layers.size(); ++i) {
    if (points[i].empty()) continue;
    top[i].assign(num_pixels, -std::numeric_limits<float>::infinity());
    const double half_px = layers[i].resolution_m / 2 / view.pixel_m;
    for (const Eigen::Vector3d& p : points[i]) {
      // The voxel's square [x - r/2, x + r/2] in pixel units; a rotated voxel
      // is drawn as its axis-aligned square, which keeps rotated walls closed.
      const double cx = (p.x() - x_min) / view.pixel_m, cy = (y_max - p.y()) / view.pixel_m;
      const int c0 = std::max(0, static_cast<int>(std::floor(cx - half_px + kEdgeEps)));
      const int c1 = std::min(
          width - 1, std::max(c0, static_cast<int>(std::ceil(cx + half_px - kEdgeEps)) - 1));
      const int r0 = std::max(0, static_cast<int>(std::floor(cy - half_px + kEdgeEps)));
      const int r1 = std::min(
          height - 1, std::max(r0, static_cast<int>(std::ceil(cy + half_px - kEdgeEps)) - 1));
      for (int r = r0; r <= r1; ++r) {
        for (int c = c0; c <= c1; ++c) {
          float& z =
              top[i][static_cast<size_t>(r) * static_cast<size_t>(width) + static_cast<size_t>(c)];
          z = std::max(z, static_cast<float>(p.z()));
        }
      }
      ++view.voxels;
    }
  }

  // Shade: brightness grows linearly with height over [z_min, z_max].
  const double z_range = z_max - z_min;
  for (int r = 0; r < height; ++r) {
    for (int c = 0; c < width; ++c) {
      const size_t at =
          static_cast<size_t>(r) * static_cast<size_t>(width) + static_cast<size_t>(c);
      double sum[3] = {0, 0, 0};
      int n = 0;
      for (size_t i = 0; i < layers.size(); ++i) {
        if (top[i].empty() || !std::isfinite(top[i][at])) continue;
        const double h = z_range > 0 ? (top[i][at] - z_min) / z_range : 1.0;
        const Rgb s = Shade(layers[i].colour,
                            kMinBrightness + (1 - kMinBrightness) * std::clamp(h, 0.0, 1.0));
        sum[0] += s.r, sum[1] += s.g, sum[2] += s.b;
        ++n;
      }
      if (n == 0) continue;
      view.map.Set(c, r,
                   {static_cast<uint8_t>(std::lround(sum[0] / n)),
                    static_cast<uint8_t>(std::lround(sum[1] / n)),
                    static_cast<uint8_t>(std::lround(sum[2] / n))});
    }
  }
  return view;
}

double ScaleBarLengthM(double width_m) {
  const double limit = 0.4 * width_m;
  if (!(limit > 0) || !std::isfinite(limit)) return 0;
  double best = 0;
  for (double decade = std::pow(10.0, std::floor(std::log10(limit)) - 1); decade <= limit * 1.0001;
       decade *= 10) {
    for (double m : {1.0, 2.0, 5.0}) {
      if (decade * m <= limit * (1 + 1e-9)) best = std::max(best, decade * m);
    }
  }
  return best;
}

bool ImageFormatFromPath(const std::string& path, ImageFormat* format) {
  const size_t dot = path.find_last_of('.');
  if (dot == std::string::npos) return false;
  std::string ext = path.substr(dot + 1);
  for (char& ch : ext) ch = static_cast<char>(std::tolower(static_cast<unsigned char>(ch)));
  if (ext == "png")
    *format = ImageFormat::kPng;
  else if (ext == "svg")
    *format = ImageFormat::kSvg;
  else
    return false;
  return true;
}

}  // namespace mapd::client
