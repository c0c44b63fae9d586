// Thin RAII and I/O helpers around cairo, so that the renderers draw with
// cairo's API and never manage surfaces or byte streams by hand.
#ifndef MAPD_CLIENT_CAIRO_CANVAS_H_
#define MAPD_CLIENT_CAIRO_CANVAS_H_

#include <cairo.h>

#include <memory>
#include <string>

#include "client/rgb_image.h"
#include "common/status.h"

namespace mapd::client {

struct CairoSurfaceDeleter {
  void operator()(cairo_surface_t* s) const { cairo_surface_destroy(s); }
};
struct CairoDeleter {
  void operator()(cairo_t* c) const { cairo_destroy(c); }
};
using CairoSurface = std::unique_ptr<cairo_surface_t, CairoSurfaceDeleter>;
using Cairo = std::unique_ptr<cairo_t, CairoDeleter>;

// A surface and its drawing context; `bytes` collects an SVG surface's output
// (cairo writes it through a stream callback as it goes and at Finish()).
class Canvas {
 public:
  // An RGB raster of width x height pixels (no alpha: PNG colour type 2).
  static Canvas Raster(int width, int height);
  // An SVG document width x height px.
  static Canvas Svg(double width_px, double height_px);

  cairo_t* cr() const { return cr_.get(); }
  cairo_surface_t* surface() const { return surface_.get(); }

  // The PNG file of a Raster canvas.
  StatusOr<std::string> Png();
  // The SVG file of an Svg canvas (ends the document).
  StatusOr<std::string> FinishSvg();

 private:
  Canvas() = default;
  Status CheckStatus() const;

  std::unique_ptr<std::string> bytes_ =
      std::make_unique<std::string>();  // stable address for the callback
  CairoSurface surface_;
  Cairo cr_;
};

// Sets the source colour.
inline void SetColour(cairo_t* cr, Rgb c, double alpha = 1.0) {
  cairo_set_source_rgba(cr, c.r / 255.0, c.g / 255.0, c.b / 255.0, alpha);
}
// "#1f77b4" -> colour; black for anything else.
Rgb ParseHexColour(const char* hex);

// An image surface holding `image`, pixel for pixel (nothing when it is empty).
CairoSurface ToSurface(const RgbImage& image);

}  // namespace mapd::client

#endif  // MAPD_CLIENT_CAIRO_CANVAS_H_
