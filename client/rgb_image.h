// A plain 8-bit RGB raster: the map area of a voxel rendering, computed pixel
// by pixel before cairo frames it (client/cairo_canvas.h). Pixel (0, 0) is the
// top left.
#ifndef MAPD_CLIENT_RGB_IMAGE_H_
#define MAPD_CLIENT_RGB_IMAGE_H_

#include <cstdint>
#include <string>
#include <vector>

namespace mapd::client {

struct Rgb {
  uint8_t r = 0, g = 0, b = 0;
  bool operator==(const Rgb& o) const { return r == o.r && g == o.g && b == o.b; }
  bool operator!=(const Rgb& o) const { return !(*this == o); }
};

class RgbImage {
 public:
  RgbImage() = default;
  // REQUIRES: width, height >= 0.
  RgbImage(int width, int height, Rgb fill);

  int width() const { return width_; }
  int height() const { return height_; }
  // Row-major, 3 bytes per pixel, no padding.
  const std::vector<uint8_t>& bytes() const { return bytes_; }

  // REQUIRES: Contains(x, y).
  Rgb At(int x, int y) const;
  bool Contains(int x, int y) const { return x >= 0 && y >= 0 && x < width_ && y < height_; }
  // Out-of-image pixels are ignored.
  void Set(int x, int y, Rgb colour);

 private:
  int width_ = 0, height_ = 0;
  std::vector<uint8_t> bytes_;
};

}  // namespace mapd::client

#endif  // MAPD_CLIENT_RGB_IMAGE_H_
