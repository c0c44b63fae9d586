// A 5x7 pixel font for the labels of raster images (legend, scale bar), so
// that a PNG rendering needs no font library. Covers digits, letters (lower
// case is drawn as upper case) and the punctuation of file names and units.
#ifndef MAPD_CLIENT_BITMAP_FONT_H_
#define MAPD_CLIENT_BITMAP_FONT_H_

#include <array>
#include <cstdint>
#include <string>

namespace mapd::client {

inline constexpr int kGlyphWidthPx = 5;
inline constexpr int kGlyphHeightPx = 7;
inline constexpr int kGlyphAdvancePx = 6;  // glyph plus one column of spacing

// Rows top to bottom; bit 4 is the leftmost pixel. A character without a
// glyph is drawn as '?'.
using GlyphRows = std::array<uint8_t, kGlyphHeightPx>;
const GlyphRows& Glyph(char c);

// Width in pixels of `text` drawn at `scale` (each font pixel a scale x scale block).
inline int TextWidthPx(const std::string& text, int scale) {
  return text.empty() ? 0 : (static_cast<int>(text.size()) * kGlyphAdvancePx - 1) * scale;
}

}  // namespace mapd::client

#endif  // MAPD_CLIENT_BITMAP_FONT_H_
