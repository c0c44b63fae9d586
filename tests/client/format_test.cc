// mapctl's output formats of the fused map: GeoJSON, SVG, table, JSON, the
// change-feed lines, and the format chosen from a file's extension.
#include "client/format.h"

#include <google/protobuf/struct.pb.h>
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "client/format_svg.h"
#include "client/support/parse_json.h"
#include "client/support/svg_facts.h"

namespace mapd::client {
namespace {

namespace pb = mapserver::v1;

pb::FusedFeature Feature(uint64_t id, pb::FeatureKind kind, double ax, double ay, double bx,
                         double by, uint32_t support, std::vector<std::string> robots) {
  pb::FusedFeature f;
  f.set_id(id);
  f.set_kind(kind);
  f.mutable_a()->set_x(ax);
  f.mutable_a()->set_y(ay);
  f.mutable_b()->set_x(bx);
  f.mutable_b()->set_y(by);
  f.set_z_min(0);
  f.set_z_max(2.5);
  f.set_support(support);
  f.set_member_count(support + 1);
  for (auto& r : robots) f.add_robots(r);
  return f;
}

FeatureList ThreeFeatures() {
  return {Feature(7, pb::FEATURE_KIND_LINE, 0, 0, 10, 0, 12, {"r1", "r2"}),
          Feature(42, pb::FEATURE_KIND_PLANE, 10, 0, 10, 8, 3, {"r1"}),
          Feature(4096, pb::FEATURE_KIND_LINE, 10, 8, 0, 8.5, 1, {"robot \"quoted\""})};
}

TEST(FormatGeoJsonTest, IsAFeatureCollectionWithOneLineStringPerFeature) {
  const google::protobuf::Struct doc = ParseJson(FormatGeoJson(ThreeFeatures()));
  EXPECT_EQ(doc.fields().at("type").string_value(), "FeatureCollection");
  const auto& features = doc.fields().at("features").list_value().values();
  ASSERT_EQ(features.size(), 3);
  for (const auto& f : features) {
    const auto& fields = f.struct_value().fields();
    EXPECT_EQ(fields.at("type").string_value(), "Feature");
    const auto& geometry = fields.at("geometry").struct_value().fields();
    EXPECT_EQ(geometry.at("type").string_value(), "LineString");
    const auto& coordinates = geometry.at("coordinates").list_value().values();
    ASSERT_EQ(coordinates.size(), 2);
    for (const auto& point : coordinates) EXPECT_EQ(point.list_value().values_size(), 2);
    const auto& props = fields.at("properties").struct_value().fields();
    for (const char* key : {"id", "kind", "support", "member_count", "z_min", "z_max", "robots"}) {
      EXPECT_TRUE(props.count(key)) << key;
    }
  }
  const auto& second = features[1].struct_value().fields();
  EXPECT_EQ(second.at("properties").struct_value().fields().at("kind").string_value(), "plane");
  EXPECT_EQ(second.at("properties").struct_value().fields().at("id").number_value(), 42);
  const auto& b =
      second.at("geometry").struct_value().fields().at("coordinates").list_value().values(1);
  EXPECT_EQ(b.list_value().values(0).number_value(), 10);
  EXPECT_EQ(b.list_value().values(1).number_value(), 8);
  const auto& robots = features[2]
                           .struct_value()
                           .fields()
                           .at("properties")
                           .struct_value()
                           .fields()
                           .at("robots")
                           .list_value();
  EXPECT_EQ(robots.values(0).string_value(), "robot \"quoted\"");
}

TEST(FormatGeoJsonTest, EmptyMapIsValid) {
  const google::protobuf::Struct doc = ParseJson(FormatGeoJson({}));
  EXPECT_EQ(doc.fields().at("features").list_value().values_size(), 0);
}

// cairo writes each stroke as a <path> in its colour; the legend adds one
// sample stroke per kind.
TEST(FormatSvgTest, HasViewBoxAndOneStrokePerFeature) {
  const std::string svg = FormatSvg(ThreeFeatures());
  EXPECT_EQ(svg.rfind("<?xml", 0), 0u);
  EXPECT_NE(svg.find("viewBox=\""), std::string::npos);
  EXPECT_EQ(testing::CountShapesOfColour(svg, "#1f77b4"), 2u + 1u);  // the two walls
  EXPECT_EQ(testing::CountShapesOfColour(svg, "#d62728"), 1u + 1u);  // the one of kind plane
  EXPECT_EQ(testing::CountShapesOfColour(svg, "#e0e0e0"), 1u);       // the grid, one path
  // y up: the map point (10, 8) is drawn at y = -8 in the metre frame.
  EXPECT_NE(svg.find("L 10 -8"), std::string::npos);
  // Scale bar and legend text are glyphs (cairo embeds their outlines).
  EXPECT_GT(testing::CountSubstr(svg, "<use"), 20u);
}

TEST(FormatSvgTest, EmptyMapStillDraws) {
  const std::string svg = FormatSvg({});
  EXPECT_NE(svg.find("viewBox=\""), std::string::npos);
  EXPECT_EQ(testing::CountShapesOfColour(svg, "#1f77b4"), 1u);  // the legend's sample only
  EXPECT_NE(svg.find("</svg>"), std::string::npos);
}

TEST(FormatTableTest, ListsEveryId) {
  const std::string table = FormatFeatureTable(ThreeFeatures());
  for (const char* id : {"\n7 ", "\n42 ", "\n4096 "})
    EXPECT_NE(table.find(id), std::string::npos) << id;
  EXPECT_NE(table.find("r1,r2"), std::string::npos);
  EXPECT_NE(table.find("3 features"), std::string::npos);
}

TEST(FormatJsonTest, RoundTripsThroughFeatureMapPage) {
  const FeatureList features = ThreeFeatures();
  pb::FeatureMapPage page;
  ASSERT_TRUE(
      google::protobuf::util::JsonStringToMessage(FormatFeatureJson(features, 9, {}, 4), &page)
          .ok());
  ASSERT_EQ(page.features_size(), 3);
  EXPECT_EQ(page.total(), 3u);
  EXPECT_EQ(page.map_version(), 9u);
  EXPECT_EQ(page.fusion_pending(), 4u) << "the server's, not always 0";
  EXPECT_EQ(page.features(1).SerializeAsString(), features[1].SerializeAsString());
}

TEST(FormatDeltaTest, OneLinePerChangeInTextAndJson) {
  pb::FeatureMapDelta d;
  d.set_map_version(42);
  d.set_resync(true);
  pb::FusedFeature* f = d.add_added();
  f->set_id(7);
  f->set_kind(pb::FEATURE_KIND_LINE);
  f->mutable_b()->set_x(2.5);
  f->set_member_count(3);
  f->add_robots("r1");
  d.add_removed(9);
  d.add_removed_planes(11);
  const std::string text = FormatDeltaLines(d, false);
  EXPECT_EQ(text,
            "v=42 resync (the full map follows)\n"
            "v=42 added feature 7 line (0.00, 0.00)-(2.50, 0.00) support 0 robots r1\n"
            "v=42 removed feature 9\n"
            "v=42 removed plane 11\n");
  const std::string json = FormatDeltaLines(d, true);
  std::vector<std::string> lines;
  for (size_t at = 0, end; (end = json.find('\n', at)) != std::string::npos; at = end + 1)
    lines.push_back(json.substr(at, end - at));
  ASSERT_EQ(lines.size(), 4u);
  EXPECT_EQ(lines[0], "{\"map_version\":42,\"change\":\"resync\"}");
  EXPECT_NE(lines[1].find("\"change\":\"added\",\"type\":\"feature\",\"id\":7,\"feature\":{"),
            std::string::npos)
      << lines[1];
  EXPECT_NE(lines[1].find("\"member_count\":3"), std::string::npos);
  EXPECT_EQ(lines[3], "{\"map_version\":42,\"change\":\"removed\",\"type\":\"plane\",\"id\":11}");
}

TEST(OutputFormatTest, GuessedFromExtension) {
  EXPECT_EQ(GuessOutputFormat("map.geojson", OutputFormat::kTable), OutputFormat::kGeoJson);
  EXPECT_EQ(GuessOutputFormat("map.json", OutputFormat::kTable), OutputFormat::kJson);
  EXPECT_EQ(GuessOutputFormat("dir/map.svg", OutputFormat::kTable), OutputFormat::kSvg);
  EXPECT_EQ(GuessOutputFormat("map.txt", OutputFormat::kTable), OutputFormat::kTable);
  OutputFormat f;
  EXPECT_TRUE(ParseOutputFormat("geojson", &f));
  EXPECT_EQ(f, OutputFormat::kGeoJson);
  EXPECT_FALSE(ParseOutputFormat("png", &f));
}

}  // namespace
}  // namespace mapd::client
