// Fused non-vertical planes in mapctl's output formats.
#include <google/protobuf/struct.pb.h>
#include <gtest/gtest.h>

#include <string>

#include "client/format.h"
#include "client/format_svg.h"
#include "client/support/parse_json.h"
#include "client/support/svg_facts.h"

namespace mapd::client {
namespace {

namespace pb = mapserver::v1;

// A floor (z = 0) spanning [0, 10] x [0, 8], counter-clockwise from above.
pb::FusedPlane Floor() {
  pb::FusedPlane p;
  p.set_id(8192);
  p.mutable_normal()->set_z(1);
  p.set_offset(0);
  for (auto [x, y] : {std::pair{0.0, 0.0}, {10.0, 0.0}, {10.0, 8.0}, {0.0, 8.0}}) {
    auto* v = p.add_boundary();
    v->set_x(x);
    v->set_y(y);
  }
  p.set_area(80);
  p.set_support(5);
  p.set_member_count(7);
  p.add_robots("r1");
  p.add_robots("r2");
  return p;
}

pb::FusedFeature Wall() {
  pb::FusedFeature f;
  f.set_id(7);
  f.set_kind(pb::FEATURE_KIND_LINE);
  f.mutable_a()->set_x(0);
  f.mutable_b()->set_x(10);
  f.set_support(4);
  return f;
}

TEST(FormatPlanesTest, GeoJsonDrawsAPlaneAsAClosedPolygonWithItsProperties) {
  for (const FeatureList& lines : {FeatureList{}, FeatureList{Wall()}}) {
    const google::protobuf::Struct doc = ParseJson(FormatGeoJson(lines, {Floor()}));
    const auto& features = doc.fields().at("features").list_value().values();
    ASSERT_EQ(static_cast<size_t>(features.size()), lines.size() + 1);
    const auto& plane = features[features.size() - 1].struct_value().fields();
    const auto& geometry = plane.at("geometry").struct_value().fields();
    EXPECT_EQ(geometry.at("type").string_value(), "Polygon");
    const auto& ring = geometry.at("coordinates").list_value().values(0).list_value().values();
    ASSERT_EQ(ring.size(), 5);  // closed: the first point again
    EXPECT_EQ(ring[4].list_value().values(0).number_value(), 0);
    EXPECT_EQ(ring[2].list_value().values(0).number_value(), 10);
    EXPECT_EQ(ring[2].list_value().values(1).number_value(), 8);
    const auto& props = plane.at("properties").struct_value().fields();
    EXPECT_EQ(props.at("kind").string_value(), "plane");
    EXPECT_EQ(props.at("id").number_value(), 8192);
    EXPECT_EQ(props.at("normal").list_value().values(2).number_value(), 1);
    for (const char* key :
         {"offset_m", "area_m2", "z_min", "z_max", "support", "member_count", "robots"}) {
      EXPECT_TRUE(props.count(key)) << key;
    }
  }
}

TEST(FormatPlanesTest, SvgDrawsTranslucentPolygonsUnderTheLines) {
  const std::string svg = FormatSvg({Wall()}, {Floor()});
  // cairo paints in drawing order: the plane's fill (#2ca02c) before the wall's stroke (#1f77b4).
  const size_t polygon = svg.find(testing::CairoRedPrefix("#2ca02c"));
  const size_t line = svg.find(testing::CairoRedPrefix("#1f77b4"));
  ASSERT_NE(polygon, std::string::npos);
  ASSERT_NE(line, std::string::npos);
  EXPECT_LT(polygon, line) << "planes are drawn first, under the lines";
  EXPECT_NE(svg.find("0.15"), std::string::npos);     // fill opacity
  EXPECT_NE(svg.find("L 10 -8"), std::string::npos);  // y up
  EXPECT_EQ(testing::CountShapesOfColour(FormatSvg({Wall()}), "#2ca02c"), 0u);
}

TEST(FormatPlanesTest, TableListsPlanesAfterTheFeatures) {
  const std::string table = FormatFeatureTable({Wall()}, {Floor()});
  EXPECT_NE(table.find("1 feature\n"), std::string::npos);
  EXPECT_NE(table.find("\n8192 "), std::string::npos);
  EXPECT_NE(table.find("(0.000, 0.000, 1.000)"), std::string::npos);
  EXPECT_NE(table.find("80.00"), std::string::npos);
  EXPECT_NE(table.find("r1,r2"), std::string::npos);
  EXPECT_NE(table.find("1 plane\n"), std::string::npos);
  EXPECT_EQ(FormatFeatureTable({Wall()}).find("PLANE"), std::string::npos);
}

TEST(FormatPlanesTest, JsonCarriesThePlanes) {
  pb::FeatureMapPage page;
  ASSERT_TRUE(
      google::protobuf::util::JsonStringToMessage(FormatFeatureJson({Wall()}, 3, {Floor()}), &page)
          .ok());
  ASSERT_EQ(page.planes_size(), 1);
  EXPECT_EQ(page.planes(0).SerializeAsString(), Floor().SerializeAsString());
}

}  // namespace
}  // namespace mapd::client
