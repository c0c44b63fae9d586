#include "client/cairo_canvas.h"

#include <cairo-svg.h>

#include <cstdio>

namespace mapd::client {
namespace {

cairo_status_t Append(void* closure, const unsigned char* data, unsigned int length) {
  static_cast<std::string*>(closure)->append(reinterpret_cast<const char*>(data), length);
  return CAIRO_STATUS_SUCCESS;
}

}  // namespace

Canvas Canvas::Raster(int width, int height) {
  Canvas c;
  c.surface_.reset(cairo_image_surface_create(CAIRO_FORMAT_RGB24, width, height));
  c.cr_.reset(cairo_create(c.surface_.get()));
  return c;
}

Canvas Canvas::Svg(double width_px, double height_px) {
  Canvas c;
  c.surface_.reset(
      cairo_svg_surface_create_for_stream(Append, c.bytes_.get(), width_px, height_px));
  cairo_svg_surface_set_document_unit(c.surface_.get(), CAIRO_SVG_UNIT_PX);
  c.cr_.reset(cairo_create(c.surface_.get()));
  return c;
}

Status Canvas::CheckStatus() const {
  cairo_status_t status = cairo_status(cr_.get());
  if (status == CAIRO_STATUS_SUCCESS) status = cairo_surface_status(surface_.get());
  if (status == CAIRO_STATUS_SUCCESS) return Status::Ok();
  return Status::Internal(std::string("cairo: ") + cairo_status_to_string(status));
}

StatusOr<std::string> Canvas::Png() {
  MAPD_RETURN_IF_ERROR(CheckStatus());
  cairo_surface_flush(surface_.get());
  std::string out;
  const cairo_status_t status = cairo_surface_write_to_png_stream(surface_.get(), Append, &out);
  if (status != CAIRO_STATUS_SUCCESS) {
    return Status::Internal(std::string("cairo cannot write the PNG: ") +
                            cairo_status_to_string(status));
  }
  return out;
}

StatusOr<std::string> Canvas::FinishSvg() {
  MAPD_RETURN_IF_ERROR(CheckStatus());
  cr_.reset();
  cairo_surface_finish(surface_.get());
  const cairo_status_t status = cairo_surface_status(surface_.get());
  if (status != CAIRO_STATUS_SUCCESS) {
    return Status::Internal(std::string("cairo cannot write the SVG: ") +
                            cairo_status_to_string(status));
  }
  return std::move(*bytes_);
}

Rgb ParseHexColour(const char* hex) {
  unsigned r = 0, g = 0, b = 0;
  if (std::sscanf(hex, "#%02x%02x%02x", &r, &g, &b) != 3) return {};
  return {static_cast<uint8_t>(r), static_cast<uint8_t>(g), static_cast<uint8_t>(b)};
}

CairoSurface ToSurface(const RgbImage& image) {
  CairoSurface surface(
      cairo_image_surface_create(CAIRO_FORMAT_RGB24, image.width(), image.height()));
  if (image.width() <= 0 || image.height() <= 0) return surface;
  cairo_surface_flush(surface.get());
  unsigned char* data = cairo_image_surface_get_data(surface.get());
  const int stride = cairo_image_surface_get_stride(surface.get());
  for (int y = 0; y < image.height(); ++y) {
    auto* row = reinterpret_cast<uint32_t*>(data + static_cast<ptrdiff_t>(y) * stride);
    for (int x = 0; x < image.width(); ++x) {
      const Rgb c = image.At(x, y);
      row[x] = (uint32_t{c.r} << 16) | (uint32_t{c.g} << 8) |
               uint32_t{c.b};  // RGB24: native-endian xRGB
    }
  }
  cairo_surface_mark_dirty(surface.get());
  return surface;
}

}  // namespace mapd::client
