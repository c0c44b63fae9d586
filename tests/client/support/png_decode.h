// Reads a PNG file with cairo (libpng underneath) into plain RGB bytes, for
// tests that check the pixels mapctl draws. Header-only; link cairo.
#ifndef MAPD_TESTS_CLIENT_SUPPORT_PNG_DECODE_H_
#define MAPD_TESTS_CLIENT_SUPPORT_PNG_DECODE_H_

#include <cairo.h>

#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

namespace mapd::testing {

struct DecodedPng {
  int width = 0, height = 0;
  std::vector<uint8_t> rgb;  // row-major, 3 bytes per pixel
  uint8_t r(int x, int y) const { return rgb[(static_cast<size_t>(y) * width + x) * 3]; }
  uint8_t g(int x, int y) const { return rgb[(static_cast<size_t>(y) * width + x) * 3 + 1]; }
  uint8_t b(int x, int y) const { return rgb[(static_cast<size_t>(y) * width + x) * 3 + 2]; }
};

// False with `*error` set when `file` is not a PNG cairo can read.
inline bool DecodePng(const std::string& file, DecodedPng* out, std::string* error) {
  struct Reader {
    const std::string* file;
    size_t at = 0;
  } reader{&file};
  const auto read = [](void* closure, unsigned char* data, unsigned int length) {
    auto* r = static_cast<Reader*>(closure);
    if (r->file->size() - r->at < length) return CAIRO_STATUS_READ_ERROR;
    std::memcpy(data, r->file->data() + r->at, length);
    r->at += length;
    return CAIRO_STATUS_SUCCESS;
  };
  cairo_surface_t* surface = cairo_image_surface_create_from_png_stream(read, &reader);
  if (cairo_surface_status(surface) != CAIRO_STATUS_SUCCESS) {
    *error =
        std::string("not a readable PNG: ") + cairo_status_to_string(cairo_surface_status(surface));
    cairo_surface_destroy(surface);
    return false;
  }
  out->width = cairo_image_surface_get_width(surface);
  out->height = cairo_image_surface_get_height(surface);
  out->rgb.clear();
  const int stride = cairo_image_surface_get_stride(surface);
  const unsigned char* data = cairo_image_surface_get_data(surface);
  for (int y = 0; y < out->height; ++y) {
    const auto* row = reinterpret_cast<const uint32_t*>(data + static_cast<size_t>(y) * stride);
    for (int x = 0; x < out->width; ++x) {
      out->rgb.push_back(
          static_cast<uint8_t>(row[x] >> 16));  // opaque pixels: no premultiplication to undo
      out->rgb.push_back(static_cast<uint8_t>(row[x] >> 8));
      out->rgb.push_back(static_cast<uint8_t>(row[x]));
    }
  }
  cairo_surface_destroy(surface);
  return true;
}

}  // namespace mapd::testing

#endif  // MAPD_TESTS_CLIENT_SUPPORT_PNG_DECODE_H_
