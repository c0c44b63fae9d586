// The top-down voxel renderer of mapctl: PNG files read back with cairo, pixels of tiny known
// scenes, bounds, pixel size, scale bar, legend, and the transform helpers.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "client/rgb_image.h"
#include "client/support/png_decode.h"
#include "client/support/svg_facts.h"
#include "client/voxel_render.h"
#include "geometry/rigid3.h"

namespace mapd::client {
namespace {

using testing::DecodedPng;
using testing::DecodePng;
using ::testing::HasSubstr;

const Rgb kWhite{255, 255, 255};

Rgb Scaled(Rgb c, double f) {
  return {static_cast<uint8_t>(std::lround(c.r * f)), static_cast<uint8_t>(std::lround(c.g * f)),
          static_cast<uint8_t>(std::lround(c.b * f))};
}

// ---------------------------------------------------------------------------
// Top view

// One pixel per voxel: no magnification of small maps.
RenderOptions Unmagnified() {
  RenderOptions options;
  options.min_map_px = 1;
  return options;
}

// Three 1 m voxels: two on the floor (z 0.5) at x 0.5 and 2.5, one high (z 2.5)
// at (2.5, 1.5). Bounds (faces) x [0, 3], y [0, 2]: a 3 x 2 px map at 1 m/px.
VoxelLayer TinyLayer(Rgb colour) {
  VoxelLayer layer;
  layer.label = "tiny";
  layer.colour = colour;
  layer.resolution_m = 1.0;
  layer.centres_m = {{0.5, 0.5, 0.5}, {2.5, 0.5, 0.5}, {2.5, 1.5, 2.5}};
  return layer;
}

TEST(RenderTopViewTest, PixelsOfATinyKnownScene) {
  const Rgb red{200, 0, 0};
  StatusOr<TopView> view = RenderTopView({TinyLayer(red)}, Unmagnified());
  ASSERT_TRUE(view.ok()) << view.status().ToString();
  EXPECT_EQ(view->pixel_m, 1.0);
  ASSERT_EQ(view->map.width(), 3);
  ASSERT_EQ(view->map.height(), 2);
  EXPECT_DOUBLE_EQ(view->x_min_m, 0.0);
  EXPECT_DOUBLE_EQ(view->x_max_m, 3.0);
  EXPECT_DOUBLE_EQ(view->y_min_m, 0.0);
  EXPECT_DOUBLE_EQ(view->y_max_m, 2.0);
  EXPECT_DOUBLE_EQ(view->z_min_m, 0.5);
  EXPECT_DOUBLE_EQ(view->z_max_m, 2.5);
  EXPECT_EQ(view->voxels, 3u);

  // North up: row 0 is y in [1, 2]. Lowest voxels at 35% brightness, the highest at 100%.
  EXPECT_EQ(view->map.At(0, 1), Scaled(red, 0.35));  // (0.5, 0.5)
  EXPECT_EQ(view->map.At(2, 1), Scaled(red, 0.35));  // (2.5, 0.5)
  EXPECT_EQ(view->map.At(2, 0), red);                // (2.5, 1.5), z 2.5
  EXPECT_EQ(view->map.At(1, 1), kWhite);             // nothing at (1.5, 0.5)
  EXPECT_EQ(view->map.At(0, 0), kWhite);
  EXPECT_EQ(view->map.At(1, 0), kWhite);

  int col = -1, row = -1;
  view->MetresToPixel(2.5, 1.5, &col, &row);
  EXPECT_EQ(col, 2);
  EXPECT_EQ(row, 0);
}

TEST(RenderTopViewTest, MaxHeightWinsWithinALayer) {
  VoxelLayer layer = TinyLayer({0, 0, 200});
  layer.centres_m.push_back({0.5, 0.5, 2.5});  // above the floor voxel at (0.5, 0.5)
  StatusOr<TopView> view = RenderTopView({layer}, Unmagnified());
  ASSERT_TRUE(view.ok());
  EXPECT_EQ(view->map.At(0, 1), (Rgb{0, 0, 200}));
}

TEST(RenderTopViewTest, TransformedLayersThatCoincideMixTheirColours) {
  const Rgb red{200, 0, 0}, blue{0, 0, 200};
  VoxelLayer b;
  b.label = "moved";
  b.colour = blue;
  b.resolution_m = 1.0;
  b.centres_m = {{0.5, 0.5, 2.5}};
  // Moved by (2, 1, 0) it lands on the red layer's high voxel at (2.5, 1.5, 2.5).
  b.T_view_layer = geometry::Rigid3::FromQuaternion(1, 0, 0, 0, Eigen::Vector3d(2, 1, 0));
  StatusOr<TopView> view = RenderTopView({TinyLayer(red), b}, Unmagnified());
  ASSERT_TRUE(view.ok());
  ASSERT_EQ(view->map.width(), 3);
  ASSERT_EQ(view->map.height(), 2);
  EXPECT_EQ(view->map.At(2, 0), (Rgb{100, 0, 100}));  // the mean of red and blue
  EXPECT_EQ(view->map.At(0, 1), Scaled(red, 0.35));   // red alone
}

TEST(RenderTopViewTest, RotatedLayerKeepsAWallClosed) {
  // A 2 m wall of 0.1 m voxels along x, rotated by 45 degrees: every pixel
  // along the diagonal must be drawn (no holes from the rotation).
  VoxelLayer wall;
  wall.label = "wall";
  wall.colour = {0, 150, 0};
  wall.resolution_m = 0.1;
  for (int i = 0; i < 20; ++i) wall.centres_m.push_back({0.05 + 0.1 * i, 0.05, 0.05});
  wall.T_view_layer = geometry::Rigid3::FromQuaternion(std::cos(M_PI / 8), 0, 0, std::sin(M_PI / 8),
                                                       Eigen::Vector3d::Zero());
  StatusOr<TopView> view = RenderTopView({wall}, RenderOptions());
  ASSERT_TRUE(view.ok());
  int holes = 0;
  for (double s = 0.1; s < 1.9; s += 0.05) {  // along the rotated wall's axis
    const Eigen::Vector3d p = wall.T_view_layer * Eigen::Vector3d(s, 0.05, 0);
    int col, row;
    view->MetresToPixel(p.x(), p.y(), &col, &row);
    if (view->map.At(col, row) == kWhite) ++holes;
  }
  EXPECT_EQ(holes, 0);
}

TEST(RenderTopViewTest, ShadingIgnoresAFewOutlierHeights) {
  // 200 floor voxels at z 0.5 and 200 wall-top voxels at z 2.5, plus one stray
  // voxel at z 40: the shading range stays [0.5, 2.5], so wall tops are at full brightness.
  const Rgb green{0, 200, 0};
  VoxelLayer layer;
  layer.label = "outlier";
  layer.colour = green;
  layer.resolution_m = 1.0;
  for (int i = 0; i < 200; ++i) {
    layer.centres_m.push_back({0.5 + i, 0.5, 0.5});
    layer.centres_m.push_back({0.5 + i, 1.5, 2.5});
  }
  layer.centres_m.push_back({0.5, 2.5, 40.0});
  StatusOr<TopView> view = RenderTopView({layer}, Unmagnified());
  ASSERT_TRUE(view.ok());
  EXPECT_DOUBLE_EQ(view->z_min_m, 0.5);
  EXPECT_DOUBLE_EQ(view->z_max_m, 2.5);
  EXPECT_EQ(view->map.At(10, 1), green);                // a wall top, row 1 = y in [1, 2]
  EXPECT_EQ(view->map.At(10, 2), Scaled(green, 0.35));  // the floor
  EXPECT_EQ(view->map.At(0, 0), green);                 // the stray voxel, clamped to the brightest
}

TEST(RenderTopViewTest, PixelSizeGrowsToTheMaximumImageSize) {
  // 100 m of 5 cm voxels in a map of at most 100 px: about 1 m per pixel.
  VoxelLayer line;
  line.label = "line";
  line.colour = {0, 0, 0};
  line.resolution_m = 0.05;
  for (int i = 0; i < 2000; ++i) line.centres_m.push_back({0.025 + 0.05 * i, 0.025, 0.0});
  RenderOptions options = Unmagnified();
  options.max_map_px = 100;
  StatusOr<TopView> view = RenderTopView({line}, options);
  ASSERT_TRUE(view.ok());
  EXPECT_NEAR(view->pixel_m, 1.0, 1e-9);
  EXPECT_EQ(view->map.width(), 100);
  EXPECT_EQ(view->map.height(), 1);
  for (int x = 0; x < 100; ++x) EXPECT_NE(view->map.At(x, 0), kWhite) << x;

  // Without the cap the pixel is the voxel size.
  options.max_map_px = 4096;
  view = RenderTopView({line}, options);
  ASSERT_TRUE(view.ok());
  EXPECT_DOUBLE_EQ(view->pixel_m, 0.05);
  EXPECT_EQ(view->map.width(), 2000);
}

TEST(RenderTopViewTest, SmallMapsAreMagnified) {
  // 3 m x 2 m of 1 m voxels with min_map_px 30: 0.1 m per pixel, each voxel 10 x 10 px.
  const Rgb red{200, 0, 0};
  RenderOptions options;
  options.min_map_px = 30;
  StatusOr<TopView> view = RenderTopView({TinyLayer(red)}, options);
  ASSERT_TRUE(view.ok());
  EXPECT_NEAR(view->pixel_m, 0.1, 1e-12);
  ASSERT_EQ(view->map.width(), 30);
  ASSERT_EQ(view->map.height(), 20);
  // The high voxel (2.5, 1.5) fills columns 20-29, rows 0-9, and nothing beyond.
  for (int y = 0; y < 10; ++y) {
    for (int x = 20; x < 30; ++x) ASSERT_EQ(view->map.At(x, y), red) << x << "," << y;
    EXPECT_EQ(view->map.At(19, y), kWhite) << y;
  }
  EXPECT_EQ(view->map.At(25, 10), Scaled(red, 0.35));  // the floor voxel below it
  // An explicit pixel size is kept.
  options.pixel_m = 0.5;
  view = RenderTopView({TinyLayer(red)}, options);
  ASSERT_TRUE(view.ok());
  EXPECT_EQ(view->map.width(), 6);
}

TEST(RenderTopViewTest, RefusesBadInputNamingIt) {
  RenderOptions options;
  options.pixel_m = -1;
  StatusOr<TopView> view = RenderTopView({TinyLayer({1, 1, 1})}, options);
  ASSERT_FALSE(view.ok());
  EXPECT_THAT(view.status().message(), HasSubstr("pixel_m"));

  options = RenderOptions();
  options.max_map_px = 4;
  EXPECT_THAT(options.Validate().message(), HasSubstr("max_map_px"));
  options = RenderOptions();
  options.min_map_px = 4096;  // above max_map_px
  EXPECT_THAT(options.Validate().message(), HasSubstr("min_map_px"));
  options = RenderOptions();
  options.text_scale = 0;
  EXPECT_THAT(options.Validate().message(), HasSubstr("text_scale"));

  EXPECT_FALSE(RenderTopView({}, RenderOptions()).ok());
  VoxelLayer empty = TinyLayer({1, 1, 1});
  empty.centres_m.clear();
  view = RenderTopView({empty}, RenderOptions());
  ASSERT_FALSE(view.ok());
  EXPECT_THAT(view.status().message(), HasSubstr("no occupied voxel"));

  VoxelLayer bad_res = TinyLayer({1, 1, 1});
  bad_res.resolution_m = 0;
  view = RenderTopView({TinyLayer({1, 1, 1}), bad_res}, RenderOptions());
  ASSERT_FALSE(view.ok());
  EXPECT_THAT(view.status().message(), HasSubstr("layers[1].resolution_m"));

  VoxelLayer nan = TinyLayer({1, 1, 1});
  nan.T_view_layer.translation.x() = std::nan("");
  view = RenderTopView({nan}, RenderOptions());
  ASSERT_FALSE(view.ok());
  EXPECT_THAT(view.status().message(), HasSubstr("not finite"));
}

TEST(ScaleBarTest, LargestNiceLengthWithinFortyPercent) {
  EXPECT_DOUBLE_EQ(ScaleBarLengthM(10), 2);    // 4 m allowed
  EXPECT_DOUBLE_EQ(ScaleBarLengthM(100), 20);  // 40 m allowed
  EXPECT_DOUBLE_EQ(ScaleBarLengthM(13), 5);    // 5.2 m allowed
  EXPECT_DOUBLE_EQ(ScaleBarLengthM(1.3), 0.5);
  EXPECT_DOUBLE_EQ(ScaleBarLengthM(2.5), 1);  // exactly 40%
  EXPECT_DOUBLE_EQ(ScaleBarLengthM(0), 0);
}

TEST(ImageFormatTest, FromTheExtension) {
  ImageFormat f = ImageFormat::kSvg;
  EXPECT_TRUE(ImageFormatFromPath("a/b.PNG", &f));
  EXPECT_EQ(f, ImageFormat::kPng);
  EXPECT_TRUE(ImageFormatFromPath("map.svg", &f));
  EXPECT_EQ(f, ImageFormat::kSvg);
  EXPECT_FALSE(ImageFormatFromPath("map.bt", &f));
  EXPECT_FALSE(ImageFormatFromPath("png", &f));
}

// ---------------------------------------------------------------------------
// Whole pictures

// A 10 m x 4 m frame of 0.5 m voxels: the map is 20 x 8 px at 0.5 m/px.
VoxelLayer Frame() {
  VoxelLayer layer;
  layer.label = "frame <1>";
  layer.colour = LayerColour(0);
  layer.resolution_m = 0.5;
  for (int i = 0; i < 20; ++i) {
    for (int j = 0; j < 8; ++j) {
      if (i == 0 || j == 0 || i == 19 || j == 7)
        layer.centres_m.push_back({0.25 + 0.5 * i, 0.25 + 0.5 * j, 1.0});
    }
  }
  return layer;
}

TEST(RenderVoxelImageTest, PngHoldsTheMapScaleBarAndLegend) {
  RenderOptions options = Unmagnified();
  options.margin_px = 10;
  options.text_scale = 1;
  const std::vector<VoxelLayer> layers = {Frame()};
  StatusOr<TopView> view = RenderTopView(layers, options);
  ASSERT_TRUE(view.ok());
  ASSERT_EQ(view->map.width(), 20);
  ASSERT_EQ(view->map.height(), 8);

  StatusOr<std::string> png = RenderVoxelImage(layers, options, ImageFormat::kPng);
  ASSERT_TRUE(png.ok()) << png.status().ToString();
  DecodedPng image;
  std::string error;
  ASSERT_TRUE(DecodePng(*png, &image, &error)) << error;
  // The legend line is wider than the map: the picture grows to hold it.
  EXPECT_GT(image.width, 20 + 2 * 10);
  EXPECT_GT(image.height, 8 + 2 * 10);
  // The map sits at (margin, margin), pixel for pixel.
  for (int y = 0; y < 8; ++y) {
    for (int x = 0; x < 20; ++x) {
      const Rgb want = view->map.At(x, y);
      ASSERT_EQ(image.r(10 + x, 10 + y), want.r) << x << "," << y;
      ASSERT_EQ(image.g(10 + x, 10 + y), want.g) << x << "," << y;
    }
  }
  // Scale bar: 10 m wide -> 2 m = 4 px, dark, starting one margin below the map.
  const int bar_y = 10 + 8 + 10;
  for (int x = 10; x < 14; ++x) EXPECT_LT(image.r(x, bar_y), 50) << x;
  EXPECT_EQ(image.r(14, bar_y), 255);
  // Somewhere below the bar the legend swatch has the layer's colour.
  bool swatch = false;
  for (int y = bar_y; y < image.height && !swatch; ++y) {
    swatch = image.r(10, y) == layers[0].colour.r && image.g(10, y) == layers[0].colour.g &&
             image.b(10, y) == layers[0].colour.b;
  }
  EXPECT_TRUE(swatch);
}

TEST(RenderVoxelImageTest, SvgEmbedsTheMapAndWritesVectorLegend) {
  VoxelLayer second = Frame();
  second.label = "second";
  second.colour = LayerColour(1);
  StatusOr<std::string> svg = RenderVoxelImage({Frame(), second}, Unmagnified(), ImageFormat::kSvg);
  ASSERT_TRUE(svg.ok()) << svg.status().ToString();
  EXPECT_EQ(svg->rfind("<?xml", 0), 0u);
  EXPECT_THAT(
      *svg,
      HasSubstr("data:image/png;base64,iVBORw0KGgo"));  // the map: a PNG (signature in base64)
  // The two legend swatches in the layers' colours (cairo paints each as a path).
  EXPECT_EQ(testing::CountSubstr(*svg, testing::CairoRedPrefix("#d55e00")), 1u);
  EXPECT_EQ(testing::CountSubstr(*svg, testing::CairoRedPrefix("#0072b2")), 1u);
  // Text is glyph outlines, one <use> per visible character: at least the
  // scale bar "2 m", the caption, both labels and the overlap note.
  EXPECT_GT(testing::CountSubstr(*svg, "<use"),
            std::string("2mframe<1>secondmixedcolour:layersoverlap").size());
  EXPECT_THAT(*svg, HasSubstr("</svg>"));
}

// The labels keep their case: "10 m" is metres, "10 M" would be something else.
TEST(RenderVoxelImageTest, LabelsKeepTheirCase) {
  for (ImageFormat format : {ImageFormat::kPng, ImageFormat::kSvg}) {
    VoxelLayer lower = Frame(), upper = Frame();
    lower.label = "room a";
    upper.label = "ROOM A";
    StatusOr<std::string> a = RenderVoxelImage({lower}, Unmagnified(), format);
    StatusOr<std::string> b = RenderVoxelImage({upper}, Unmagnified(), format);
    ASSERT_TRUE(a.ok() && b.ok());
    EXPECT_NE(*a, *b) << (format == ImageFormat::kPng ? "png" : "svg");
  }
}

}  // namespace
}  // namespace mapd::client
