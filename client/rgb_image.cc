#include "client/rgb_image.h"

#include <algorithm>

#include "client/bitmap_font.h"

namespace mapd::client {

RgbImage::RgbImage(int width, int height, Rgb fill)
    : width_(std::max(width, 0)), height_(std::max(height, 0)) {
  bytes_.resize(static_cast<size_t>(width_) * static_cast<size_t>(height_) * 3);
  for (size_t i = 0; i < bytes_.size(); i += 3) {
    bytes_[i] = fill.r;
    bytes_[i + 1] = fill.g;
    bytes_[i + 2] = fill.b;
  }
}

Rgb RgbImage::At(int x, int y) const {
  const size_t i = (static_cast<size_t>(y) * static_cast<size_t>(width_) + static_cast<size_t>(x)) * 3;
  return {bytes_[i], bytes_[i + 1], bytes_[i + 2]};
}

void RgbImage::Set(int x, int y, Rgb colour) {
  if (!Contains(x, y)) return;
  const size_t i = (static_cast<size_t>(y) * static_cast<size_t>(width_) + static_cast<size_t>(x)) * 3;
  bytes_[i] = colour.r;
  bytes_[i + 1] = colour.g;
  bytes_[i + 2] = colour.b;
}

void RgbImage::FillRect(int x, int y, int w, int h, Rgb colour) {
  const int x0 = std::max(x, 0), y0 = std::max(y, 0);
  const int x1 = std::min(x + w, width_), y1 = std::min(y + h, height_);
  for (int yy = y0; yy < y1; ++yy) {
    for (int xx = x0; xx < x1; ++xx) Set(xx, yy, colour);
  }
}

int RgbImage::DrawText(int x, int y, const std::string& text, int scale, Rgb colour) {
  int pen = x;
  for (char c : text) {
    const GlyphRows& rows = Glyph(c);
    for (int row = 0; row < kGlyphHeightPx; ++row) {
      for (int col = 0; col < kGlyphWidthPx; ++col) {
        if (rows[static_cast<size_t>(row)] & (0x10 >> col)) {
          FillRect(pen + col * scale, y + row * scale, scale, scale, colour);
        }
      }
    }
    pen += kGlyphAdvancePx * scale;
  }
  return TextWidthPx(text, scale);
}

void RgbImage::Blit(const RgbImage& src, int x, int y) {
  for (int sy = 0; sy < src.height(); ++sy) {
    for (int sx = 0; sx < src.width(); ++sx) Set(x + sx, y + sy, src.At(sx, sy));
  }
}

}  // namespace mapd::client
