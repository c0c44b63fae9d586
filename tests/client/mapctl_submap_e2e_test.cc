// mapctl's voxel-submap commands against the real mapd, as an operator would
// use them: upload two overlapping maps of a room, merge them with progress
// and a rendering, download the global map, render files; a corrupt upload is
// refused with a clear error and the server keeps serving; a merge without
// evidence is refused with the server's reason.
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <signal.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include "client/support/png_decode.h"
#include "client/support/svg_facts.h"
#include "common/octomap_scenes.h"
#include "common/process.h"
#include "common/temp_dir.h"
#include "voxel/octree_reader.h"

namespace mapd::testing {
namespace {

using ::testing::HasSubstr;
using ::testing::Not;

std::string ReadAll(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

void WriteAll(const std::string& path, const std::string& data) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out << data;
}

size_t Count(const std::string& text, const std::string& needle) {
  size_t n = 0;
  for (size_t at = text.find(needle); at != std::string::npos; at = text.find(needle, at + 1)) ++n;
  return n;
}

// The id in "submap 7: robot r1, ..." (mapctl submap upload's answer), or "" if absent.
std::string UploadedId(const std::string& out) {
  std::smatch m;
  return std::regex_search(out, m, std::regex(R"(^submap (\d+): robot)")) ? m[1].str() : "";
}

struct PrintedAlignment {
  bool found = false;
  double x = 0, y = 0, z = 0, yaw = 0, pitch = 0, roll = 0;
};

// "  submap 8: xyz (2.998, -0.501, 0.000) m, yaw/pitch/roll (20.01, 0.00, 0.00) deg, ..."
PrintedAlignment ParseAlignment(const std::string& out, const std::string& id) {
  const std::string num = R"(\s*(-?[0-9.]+))";
  const std::regex line("submap " + id + ": xyz \\(" + num + "," + num + "," + num +
                        "\\) m, yaw/pitch/roll \\(" + num + "," + num + "," + num + "\\) deg");
  std::smatch m;
  PrintedAlignment a;
  if (!std::regex_search(out, m, line)) return a;
  a.found = true;
  a.x = std::stod(m[1]), a.y = std::stod(m[2]), a.z = std::stod(m[3]);
  a.yaw = std::stod(m[4]), a.pitch = std::stod(m[5]), a.roll = std::stod(m[6]);
  return a;
}

::testing::AssertionResult IsValidPng(const std::string& path) {
  DecodedPng png;
  std::string error;
  if (!DecodePng(ReadAll(path), &png, &error))
    return ::testing::AssertionFailure() << path << ": " << error;
  if (png.width < 20 || png.height < 20) {
    return ::testing::AssertionFailure() << path << ": only " << png.width << "x" << png.height;
  }
  size_t coloured = 0;  // pixels that are neither white nor grey: voxels drawn
  for (size_t i = 0; i + 2 < png.rgb.size(); i += 3) {
    if (png.rgb[i] != png.rgb[i + 1] || png.rgb[i + 1] != png.rgb[i + 2]) ++coloured;
  }
  if (coloured < 500)
    return ::testing::AssertionFailure() << path << ": only " << coloured << " coloured pixels";
  return ::testing::AssertionSuccess();
}

// Two overlapping views of the shared test room (common/octomap_scenes.h):
// A in the map frame, B a quarter turn and a shift away (x in [2, 10)); and a
// bare floor, which has no corner to match (a merge with it must be refused).
struct RoomMaps {
  std::string a_bt, b_bt, floor_bt;
  Eigen::Isometry3d T_a_b = Eigen::Isometry3d::Identity();  // maps B into A
};

RoomMaps MakeRoomMaps() {
  RoomMaps maps;
  const RoomScene room;
  maps.T_a_b = YawTranslation(M_PI / 2, Eigen::Vector3d(2.0, -1.0, 0.0));
  maps.a_bt = RoomSubmap(room, 0, 8, Eigen::Isometry3d::Identity());
  maps.b_bt = RoomSubmap(room, 2, 10, maps.T_a_b);
  RoomScene floor;
  floor.size_x_m = 4.0;
  floor.size_y_m = 4.0;
  floor.floor_only = true;
  maps.floor_bt = RoomSubmap(floor, 0, 4, Eigen::Isometry3d::Identity());
  return maps;
}

class MapctlSubmapE2eTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() { maps_ = new RoomMaps(MakeRoomMaps()); }
  static void TearDownTestSuite() {
    delete maps_;
    maps_ = nullptr;
  }

  void SetUp() override {
    WriteAll(a_bt_, maps_->a_bt);
    WriteAll(b_bt_, maps_->b_bt);
    WriteAll(floor_bt_, maps_->floor_bt);
    mapd_ = StartMapd(dir_.File("map.db"), {}, MAPD_BINARY);
    ASSERT_GT(mapd_.port, 0) << "mapd did not come up:\n" << mapd_.log();
  }
  void TearDown() override {
    if (mapd_.pid > 0) Stop(mapd_.pid, SIGKILL);
  }

  CommandResult Mapctl(std::vector<std::string> args) {
    args.insert(args.begin(), {MAPCTL_BINARY, "--server", mapd_.address});
    return RunCommand(args, "");
  }
  // Uploads and returns the new id ("" on failure, reported).
  std::string Upload(const std::string& path, const std::string& robot) {
    CommandResult r = Mapctl({"submap", "upload", path, "--robot", robot});
    EXPECT_EQ(r.exit_code, 0) << r.out << r.err;
    const std::string id = UploadedId(r.out);
    EXPECT_FALSE(id.empty()) << r.out;
    return id;
  }

  static RoomMaps* maps_;
  TempDir dir_;
  const std::string a_bt_ = dir_.File("room_a.bt"), b_bt_ = dir_.File("room_b.bt"),
                    floor_bt_ = dir_.File("floor.bt");
  MapdProcess mapd_;
};

RoomMaps* MapctlSubmapE2eTest::maps_ = nullptr;

TEST_F(MapctlSubmapE2eTest, GeneratedMapsAreValidOctrees) {
  // Guards the fixture: the maps parse with the server's own reader.
  EXPECT_TRUE(voxel::ValidateOctree(maps_->a_bt).ok());
  EXPECT_TRUE(voxel::ValidateOctree(maps_->b_bt).ok());
  EXPECT_TRUE(voxel::ValidateOctree(maps_->floor_bt).ok());
}

TEST_F(MapctlSubmapE2eTest, UploadMergeRenderAndDownload) {
  const std::string id_a = Upload(a_bt_, "r1");
  const std::string id_b = Upload(b_bt_, "r2");
  ASSERT_FALSE(id_a.empty());
  ASSERT_FALSE(id_b.empty());

  CommandResult r = Mapctl({"submaps"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_THAT(r.out, HasSubstr("room_a"));
  EXPECT_THAT(r.out, HasSubstr("room_b"));

  // Merge with progress and a rendering of both inputs in the merged frame.
  const std::string merge_png = dir_.File("merge.png");
  r = Mapctl({"merge", id_a, id_b, "--wait", "--render", merge_png});
  ASSERT_EQ(r.exit_code, 0) << r.out << r.err << mapd_.log();
  EXPECT_THAT(r.out, HasSubstr("%"));  // progress lines "merge: <stage> NN%"
  EXPECT_GE(Count(r.out, "merge: "), 2u) << r.out;
  EXPECT_THAT(r.out, HasSubstr("accepted"));
  const PrintedAlignment b = ParseAlignment(r.out, id_b);
  ASSERT_TRUE(b.found) << r.out;
  const Eigen::Vector3d t = maps_->T_a_b.translation();
  const double truth_yaw =
      std::atan2(maps_->T_a_b.linear()(1, 0), maps_->T_a_b.linear()(0, 0)) * 180 / M_PI;
  // Within 1.5 voxels and 1.5 degrees of the generated transform.
  EXPECT_NEAR(b.x, t.x(), 0.15) << r.out;
  EXPECT_NEAR(b.y, t.y(), 0.15) << r.out;
  EXPECT_NEAR(b.z, t.z(), 0.15) << r.out;
  EXPECT_NEAR(b.yaw, truth_yaw, 1.5) << r.out;
  EXPECT_NEAR(b.pitch, 0.0, 1.5) << r.out;
  EXPECT_NEAR(b.roll, 0.0, 1.5) << r.out;
  const PrintedAlignment a = ParseAlignment(r.out, id_a);
  if (a.found) {  // the reference submap, if listed, is the identity
    EXPECT_NEAR(a.x, 0.0, 1e-3);
    EXPECT_NEAR(a.yaw, 0.0, 1e-3);
  }
  EXPECT_THAT(r.out, HasSubstr("rendered 2 layers"));
  EXPECT_TRUE(IsValidPng(merge_png));

  // The merged map is listed apart from the uploads and is no merge input.
  r = Mapctl({"submaps"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_THAT(r.out, HasSubstr("2 uploaded submaps"));
  const size_t apart = r.out.find("merged maps (outputs of merges");
  ASSERT_NE(apart, std::string::npos) << r.out;
  EXPECT_NE(r.out.find("@merged", apart), std::string::npos) << r.out;
  EXPECT_EQ(r.out.find("@merged"), r.out.find("@merged", apart)) << "only in the merged table";
  const std::string merged_id = r.out.substr(r.out.find('\n', apart) + 1);
  const std::string first_row = merged_id.substr(merged_id.find('\n') + 1);
  const std::string id_merged = first_row.substr(0, first_row.find(' '));
  r = Mapctl({"merge", id_a, id_merged, "--wait"});
  EXPECT_NE(r.exit_code, 0);
  EXPECT_THAT(r.err, HasSubstr("is the output of a merge, not an upload")) << r.out << r.err;

  // The global map: a .bt that the server's reader accepts, and its rendering.
  const std::string global_bt = dir_.File("world.bt"), global_svg = dir_.File("world.svg");
  r = Mapctl({"global-map", "-o", global_bt, "--render", global_svg});
  ASSERT_EQ(r.exit_code, 0) << r.out << r.err;
  // The union of the two uploads the merge placed, not its output.
  EXPECT_THAT(r.out, HasSubstr("global map v1: the union of submaps " + id_a + ", "));
  const std::string world = ReadAll(global_bt);
  StatusOr<voxel::OctreeSummary> summary = voxel::ValidateOctree(world);
  ASSERT_TRUE(summary.ok()) << summary.status().ToString();
  EXPECT_NEAR(summary->resolution, 0.1, 1e-6);
  const std::string svg = ReadAll(global_svg);
  EXPECT_EQ(svg.rfind("<?xml", 0), 0u);
  EXPECT_THAT(svg, HasSubstr("<svg "));
  EXPECT_THAT(svg, HasSubstr("data:image/png;base64,"));
  // One layer: one legend swatch in the first layer colour (labels are glyph outlines).
  EXPECT_EQ(CountSubstr(svg, CairoRedPrefix("#d55e00")), 1u);
  EXPECT_THAT(r.out, HasSubstr("rendered 1 layer "));

  // Local files need no server.
  const std::string both_png = dir_.File("both.png");
  r = RunCommand({MAPCTL_BINARY, "render", a_bt_, b_bt_, "-o", both_png});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(IsValidPng(both_png));
}

struct Pgm {
  int width = 0, height = 0;
  std::string pixels;  // row 0 first (the top of the map)
  unsigned char at(int col, int row) const {
    return static_cast<unsigned char>(pixels[static_cast<size_t>(row) * width + col]);
  }
};

// A binary PGM as mapctl writes it ("P5\nW H\n255\n" then W x H bytes).
bool ParsePgm(const std::string& data, Pgm* out) {
  std::istringstream in(data);
  std::string magic;
  int max = 0;
  if (!(in >> magic >> out->width >> out->height >> max) || magic != "P5" || max != 255)
    return false;
  in.get();  // the one whitespace after the header
  out->pixels = data.substr(static_cast<size_t>(in.tellg()));
  return out->pixels.size() == static_cast<size_t>(out->width) * out->height;
}

TEST_F(MapctlSubmapE2eTest, OccupancyGridOfTheGlobalMapAndOfASubmap) {
  const std::string grid = dir_.File("grid");
  // Before any merge there is no global map: said so, nothing written.
  CommandResult r = Mapctl({"occupancy-grid", "-o", grid});
  EXPECT_EQ(r.exit_code, 1) << r.out << r.err;
  EXPECT_THAT(r.err, HasSubstr("no global map yet"));
  EXPECT_FALSE(std::filesystem::exists(grid + ".pgm"));
  // A reversed band is a usage error, before anything is asked of the server.
  r = Mapctl({"occupancy-grid", "-o", grid, "--z-min", "2", "--z-max", "1"});
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_THAT(r.err, HasSubstr("--z-min"));

  const std::string id_a = Upload(a_bt_, "r1");
  const std::string id_b = Upload(b_bt_, "r2");
  ASSERT_FALSE(id_a.empty());
  ASSERT_FALSE(id_b.empty());
  r = Mapctl({"merge", id_a, id_b});
  ASSERT_EQ(r.exit_code, 0) << r.out << r.err << mapd_.log();

  // The merged room in A's frame (the map frame): 10 m x 8 m, walls on all sides.
  r = Mapctl({"occupancy-grid", "-o", grid + ".yaml"});
  ASSERT_EQ(r.exit_code, 0) << r.out << r.err;
  EXPECT_THAT(r.out, HasSubstr("grid.pgm"));
  const std::string yaml = ReadAll(grid + ".yaml");
  EXPECT_THAT(yaml, HasSubstr("image: grid.pgm\n"));
  EXPECT_THAT(yaml, HasSubstr("mode: trinary\n"));
  EXPECT_THAT(yaml, HasSubstr("resolution: 0.1\n"));
  EXPECT_THAT(yaml, HasSubstr("negate: 0\n"));
  EXPECT_THAT(yaml, HasSubstr("occupied_thresh: 0.65\n"));
  EXPECT_THAT(yaml, HasSubstr("free_thresh: 0.196\n"));
  std::smatch m;
  ASSERT_TRUE(std::regex_search(yaml, m, std::regex(R"(origin: \[(\S+), (\S+), 0\.0\])"))) << yaml;
  const double ox = std::stod(m[1]), oy = std::stod(m[2]);
  EXPECT_NEAR(ox, 0.0, 0.15);  // within the merge's accuracy of the room's corner
  EXPECT_NEAR(oy, 0.0, 0.15);
  Pgm pgm;
  ASSERT_TRUE(ParsePgm(ReadAll(grid + ".pgm"), &pgm));
  EXPECT_NEAR(pgm.width, 100, 2);
  EXPECT_NEAR(pgm.height, 80, 2);
  // Pixel of map point (x, y): row 0 is the largest y.
  const auto pixel = [&](double x, double y) {
    const int col = static_cast<int>(std::floor((x - ox) / 0.1));
    const int row = pgm.height - 1 - static_cast<int>(std::floor((y - oy) / 0.1));
    return pgm.at(col, row);
  };
  EXPECT_EQ(pixel(5.05, 7.95), 0);  // the wall at y = 8: the top rows
  EXPECT_EQ(pixel(5.05, 0.05), 0);  // the wall at y = 0
  EXPECT_EQ(pixel(0.05, 4.05), 0);
  EXPECT_EQ(pixel(7.05, 1.05), 254);  // open floor
  EXPECT_EQ(pixel(5.25, 5.85), 0);    // a tall box's side in the upper half ...
  EXPECT_EQ(pixel(5.25, 2.15), 254);  // ... not mirrored into the lower half
  size_t black_top = 0;
  for (int col = 0; col < pgm.width; ++col) black_top += pgm.at(col, 0) == 0 ? 1 : 0;
  EXPECT_GT(black_top, static_cast<size_t>(pgm.width) * 8 / 10);

  // No occupied voxel above the room: said so with the heights that exist.
  r = Mapctl({"occupancy-grid", "-o", grid, "--z-min", "5", "--z-max", "6"});
  EXPECT_EQ(r.exit_code, 1) << r.out << r.err;
  EXPECT_THAT(r.err, HasSubstr("no occupied voxel between z 5 and 6 m"));

  // One submap, in its own frame, at a coarser resolution.
  const std::string sub = dir_.File("sub");
  r = Mapctl({"occupancy-grid", "-o", sub, "--source", "submap", id_b, "--resolution", "0.2"});
  ASSERT_EQ(r.exit_code, 0) << r.out << r.err;
  EXPECT_THAT(ReadAll(sub + ".yaml"), HasSubstr("resolution: 0.2\n"));
  ASSERT_TRUE(ParsePgm(ReadAll(sub + ".pgm"), &pgm));
  EXPECT_NEAR(pgm.width, 40, 1);  // B: 8 m of the room, a quarter turn away
  EXPECT_NEAR(pgm.height, 40, 1);
  r = Mapctl({"occupancy-grid", "-o", sub, "--source", "submap", "999"});
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_THAT(r.err, HasSubstr("NOT_FOUND"));
  // One word for the source (quoted, or submap:ID) does the same (issue 43 item 10).
  for (const std::string& one_word : {"submap " + id_b, "submap:" + id_b}) {
    r = Mapctl({"occupancy-grid", "-o", sub, "--source", one_word, "--resolution", "0.2"});
    EXPECT_EQ(r.exit_code, 0) << one_word << ": " << r.out << r.err;
  }
  r = Mapctl({"occupancy-grid", "-o", sub, "--source", "moon"});
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_THAT(r.err, HasSubstr("got 'moon'"));
  // The fused walls are in the map frame, a submap in its own: not mixed.
  r = Mapctl({"occupancy-grid", "-o", sub, "--source", "submap", id_b, "--lines"});
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_THAT(r.err, HasSubstr("--source global only"));

  // --lines: the fused walls of a simulated robot drawn in, growing the grid.
  r = Mapctl({"simulate", "--robots", "1", "--scans", "40"});
  ASSERT_EQ(r.exit_code, 0) << r.out << r.err;
  r = Mapctl({"occupancy-grid", "-o", grid, "--lines"});
  ASSERT_EQ(r.exit_code, 0) << r.out << r.err;
  ASSERT_TRUE(std::regex_search(r.out, m, std::regex(R"((\d+) fused lines drawn)"))) << r.out;
  EXPECT_GT(std::stoi(m[1]), 3);
}

TEST_F(MapctlSubmapE2eTest, CorruptUploadIsRefusedAndTheServerKeepsServing) {
  // Half a file: the octree stream ends early.
  const std::string truncated = dir_.File("truncated.bt");
  WriteAll(truncated, maps_->a_bt.substr(0, maps_->a_bt.size() / 2));
  CommandResult r = Mapctl({"submap", "upload", truncated, "--robot", "r1"});
  EXPECT_EQ(r.exit_code, 1) << r.out << r.err;
  EXPECT_THAT(r.err, HasSubstr("truncated.bt"));
  EXPECT_THAT(r.err, HasSubstr("INVALID_ARGUMENT"));
  EXPECT_EQ(Count(r.err, "\n"), 1u) << "one line: " << r.err;

  // A header that lies about the resolution.
  std::string bad = maps_->a_bt;
  const size_t res = bad.find("\nres ");
  ASSERT_NE(res, std::string::npos);
  bad.replace(res, 5, "\nres -");
  const std::string negative = dir_.File("negative.bt");
  WriteAll(negative, bad);
  r = Mapctl({"submap", "upload", negative, "--robot", "r1"});
  EXPECT_EQ(r.exit_code, 1) << r.out << r.err;
  EXPECT_THAT(r.err, HasSubstr("INVALID_ARGUMENT"));

  // Still serving: the listing works and a good upload is stored.
  r = Mapctl({"submaps"});
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_THAT(r.out, Not(HasSubstr("truncated")));
  EXPECT_FALSE(Upload(a_bt_, "r1").empty());

  // mapctl's own reader refuses the same file: a bad input file is exit 2.
  r = RunCommand({MAPCTL_BINARY, "render", truncated, "-o", dir_.File("t.png")});
  EXPECT_EQ(r.exit_code, 2) << r.out << r.err;
  EXPECT_THAT(r.err, HasSubstr("truncated.bt"));
  EXPECT_THAT(r.err, HasSubstr("INVALID_ARGUMENT"));
  EXPECT_FALSE(std::filesystem::exists(dir_.File("t.png")));
}

TEST_F(MapctlSubmapE2eTest, MergeWithoutEvidenceIsRefusedWithTheReason) {
  const std::string id_a = Upload(a_bt_, "r1");
  const std::string id_floor = Upload(floor_bt_, "r3");
  ASSERT_FALSE(id_a.empty());
  ASSERT_FALSE(id_floor.empty());
  const std::string png = dir_.File("refused.png");
  CommandResult r = Mapctl({"merge", id_a, id_floor, "--wait", "--render", png});
  EXPECT_EQ(r.exit_code, 1) << r.out << r.err;
  EXPECT_THAT(r.err, HasSubstr("merge refused"));
  EXPECT_THAT(r.err, HasSubstr("FAILED_PRECONDITION"));
  EXPECT_THAT(r.out, Not(HasSubstr("accepted")));
  EXPECT_FALSE(std::filesystem::exists(png));
}

// The id in "merge 3 proposed (waits for review): ...", or "" if absent.
std::string MergeId(const std::string& out) {
  std::smatch m;
  return std::regex_search(out, m, std::regex(R"(merge (\d+) (proposed|accepted))")) ? m[1].str()
                                                                                     : "";
}

TEST_F(MapctlSubmapE2eTest, ReviewShowApproveRejectAndListMerges) {
  const std::string id_a = Upload(a_bt_, "r1");
  const std::string id_b = Upload(b_bt_, "r2");
  ASSERT_FALSE(id_b.empty());

  CommandResult r = Mapctl({"merge", id_a, id_b, "--review"});
  ASSERT_EQ(r.exit_code, 0) << r.out << r.err;
  EXPECT_THAT(r.out, HasSubstr("proposed (waits for review)"));
  const std::string first = MergeId(r.out);
  ASSERT_FALSE(first.empty()) << r.out;
  r = Mapctl({"global-map", "-o", dir_.File("none.bt")});
  EXPECT_EQ(r.exit_code, 1) << r.out;
  EXPECT_THAT(r.err, HasSubstr("NOT_FOUND"));

  // Shown and drawn while it waits.
  const std::string png = dir_.File("proposal.png");
  r = Mapctl({"merge", "show", first, "--render", png});
  ASSERT_EQ(r.exit_code, 0) << r.out << r.err;
  EXPECT_THAT(r.out, HasSubstr("merge " + first + ": proposed"));
  EXPECT_THAT(r.out, HasSubstr("requested by anonymous"));
  EXPECT_TRUE(ParseAlignment(r.out, id_b).found) << r.out;
  EXPECT_THAT(r.out, HasSubstr("rendered 2 layers"));
  EXPECT_TRUE(IsValidPng(png));

  r = Mapctl({"merge", "approve", first});
  ASSERT_EQ(r.exit_code, 0) << r.out << r.err;
  EXPECT_THAT(r.out, HasSubstr("merge " + first + ": accepted"));
  r = Mapctl({"merge", "approve", first});
  EXPECT_EQ(r.exit_code, 1) << r.out;
  EXPECT_THAT(r.err, HasSubstr("FAILED_PRECONDITION"));
  EXPECT_THAT(r.err, HasSubstr("is accepted"));
  EXPECT_EQ(Mapctl({"global-map", "-o", dir_.File("world.bt")}).exit_code, 0);

  // A second proposal, rejected (a reason is required).
  r = Mapctl({"merge", id_a, id_b, "--review"});
  const std::string second = MergeId(r.out);
  ASSERT_FALSE(second.empty()) << r.out << r.err;
  r = Mapctl({"merge", "reject", second});
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_THAT(r.err, HasSubstr("--reason"));
  r = Mapctl({"merge", "reject", second, "--reason", "duplicate of " + first});
  ASSERT_EQ(r.exit_code, 0) << r.out << r.err;
  EXPECT_THAT(r.out, HasSubstr("rejected"));

  r = Mapctl({"merges"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_THAT(r.out, HasSubstr("accepted"));
  EXPECT_THAT(r.out, HasSubstr("duplicate of " + first));
  EXPECT_THAT(r.out, HasSubstr("2 merges"));
  r = Mapctl({"merges", "--state", "rejected", "--json"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const nlohmann::json doc = nlohmann::json::parse(r.out);
  ASSERT_EQ(doc["merges"].size(), 1u) << r.out;
  const nlohmann::json& m = doc["merges"][0];
  EXPECT_EQ(m["id"].get<uint64_t>(), std::stoull(second));
  EXPECT_EQ(m["state"], "rejected");
  EXPECT_EQ(m["requested_by"], "anonymous");
  EXPECT_EQ(m["decided_by"], "anonymous");
  ASSERT_EQ(m["inputs"].size(), 2u);
  EXPECT_EQ(m["inputs"][1]["submap_id"].get<uint64_t>(), std::stoull(id_b));
  EXPECT_GE(m["inputs"][1]["matched_corners"].get<int>(), 4);
  EXPECT_EQ(m["inputs"][1]["t_reference_submap"]["translation"].size(), 3u);
  EXPECT_EQ(Mapctl({"merge", "show", "999"}).exit_code, 1);
  EXPECT_EQ(Mapctl({"merges", "--state", "maybe"}).exit_code, 2);
}

TEST_F(MapctlSubmapE2eTest, SubmapGetRoundTripsAndDeleteRemoves) {
  const std::string id_a = Upload(a_bt_, "r1");
  ASSERT_FALSE(id_a.empty());
  const std::string out = dir_.File("copy.bt");
  CommandResult r = Mapctl({"submap", "get", id_a, "-o", out});
  ASSERT_EQ(r.exit_code, 0) << r.out << r.err;
  EXPECT_THAT(r.out, HasSubstr("robot r1"));
  EXPECT_EQ(ReadAll(out), maps_->a_bt);

  r = Mapctl({"submap", "delete", id_a});
  ASSERT_EQ(r.exit_code, 0) << r.out << r.err;
  EXPECT_THAT(r.out, HasSubstr("deleted submap " + id_a));
  r = Mapctl({"submap", "get", id_a, "-o", dir_.File("gone.bt")});
  EXPECT_EQ(r.exit_code, 1) << r.out;
  EXPECT_THAT(r.err, HasSubstr("NOT_FOUND"));
  EXPECT_FALSE(std::filesystem::exists(dir_.File("gone.bt")));
  r = Mapctl({"submap", "delete", id_a});
  EXPECT_EQ(r.exit_code, 1) << r.out;
  EXPECT_THAT(r.err, HasSubstr("NOT_FOUND"));
  EXPECT_EQ(Mapctl({"submap", "delete", "abc"}).exit_code, 2);
}

// Issue 42 item 6: what a map holds, from a local file (no server needed)
// or a stored submap, with the same figures either way; junk exits 1 naming
// why, a word that is neither a file nor an id is a usage error.
TEST_F(MapctlSubmapE2eTest, SubmapInfoReadsFilesAndStoredSubmaps) {
  const voxel::SubmapSummary want = voxel::InspectSubmap(maps_->a_bt).value();
  char buf[160];
  std::snprintf(buf, sizeof buf, "resolution %.3f m, %llu occupied / %llu free voxels",
                want.resolution, static_cast<unsigned long long>(want.occupied_voxels),
                static_cast<unsigned long long>(want.free_voxels));
  const std::string figures = buf;
  CommandResult r = Mapctl({"submap", "info", a_bt_});
  ASSERT_EQ(r.exit_code, 0) << r.out << r.err;
  EXPECT_THAT(r.out, HasSubstr(a_bt_ + ": OctoMap .bt, " + figures)) << r.out;

  const std::string id_a = Upload(a_bt_, "r1");
  ASSERT_FALSE(id_a.empty());
  r = Mapctl({"submap", "info", id_a});
  ASSERT_EQ(r.exit_code, 0) << r.out << r.err;
  EXPECT_THAT(r.out,
              HasSubstr("submap " + id_a + " (robot r1, name room_a): OctoMap .bt, " + figures))
      << r.out;

  const std::string junk = dir_.File("junk.bt");
  std::ofstream(junk) << "# Octomap OcTree binary file\nres 0.1\nsize 5\ndata\nxx";
  r = Mapctl({"submap", "info", junk});
  EXPECT_EQ(r.exit_code, 1) << r.out;
  EXPECT_THAT(r.err, HasSubstr("is not a usable OctoMap file")) << r.err;
  EXPECT_EQ(Mapctl({"submap", "info", "no-such-file.bt"}).exit_code, 2);
  r = Mapctl({"submap", "info", dir_.path()});  // a directory: an error, not a crash
  EXPECT_EQ(r.exit_code, 1) << r.out << r.err;
  EXPECT_THAT(r.err, HasSubstr("is not a regular file"));
  r = Mapctl({"submap", "info", "999"});
  EXPECT_EQ(r.exit_code, 1) << r.out;
  EXPECT_THAT(r.err, HasSubstr("NOT_FOUND"));
}

// Issue 42 item 6: an operator moves a map into place and cuts regions out,
// without C++. Room b is the room's x in [2, 10) seen from T_a_b (a quarter
// turn and whole voxels); moved by T_a_b and cut to x in [2, 8), it is the
// same region of a, cut alike: the same voxels, so the same figures.
TEST_F(MapctlSubmapE2eTest, SubmapCropAndTransformMoveAMapIntoPlaceAndCutItOut) {
  const std::string id_b = Upload(b_bt_, "r2");
  ASSERT_FALSE(id_b.empty());
  const std::string b_in_a = dir_.File("b_in_a.bt");
  // From the stored submap: yaw 90, pitch 0, roll 0; then (2, -1, 0) m.
  CommandResult r = Mapctl(
      {"submap", "transform", id_b, "--rotate", "90,0,0", "--translate", "2,-1,0", "-o", b_in_a});
  ASSERT_EQ(r.exit_code, 0) << r.out << r.err;
  EXPECT_THAT(r.out, HasSubstr("wrote " + b_in_a + ": OctoMap .bt"));

  const auto cut = [&](const std::string& in, const std::string& out) {
    CommandResult c =
        Mapctl({"submap", "crop", in, "--min", "2,-1,-1", "--max", "7.99,9,3", "-o", out});
    EXPECT_EQ(c.exit_code, 0) << c.out << c.err;
    // The figures after "OctoMap .bt, ": resolution, voxels, bounds, bytes.
    const size_t at = c.out.find("OctoMap .bt, ");
    return at == std::string::npos ? c.out : c.out.substr(at);
  };
  const std::string a_cut = cut(a_bt_, dir_.File("a_cut.bt"));
  EXPECT_THAT(a_cut, HasSubstr("occupied within (2.00, 0.00, 0.00)..(8.00, ")) << a_cut;
  EXPECT_EQ(cut(b_in_a, dir_.File("b_cut.bt")), a_cut);
  EXPECT_EQ(ReadAll(dir_.File("b_cut.bt")), ReadAll(dir_.File("a_cut.bt")));

  // A .ot output keeps log-odds; the result reads back through info.
  r = Mapctl(
      {"submap", "crop", a_bt_, "--min", "0,0,0", "--max", "1,1,1", "-o", dir_.File("corner.ot")});
  ASSERT_EQ(r.exit_code, 0) << r.out << r.err;
  r = Mapctl({"submap", "info", dir_.File("corner.ot")});
  EXPECT_EQ(r.exit_code, 0) << r.out << r.err;
  EXPECT_THAT(r.out, HasSubstr("OctoMap .ot"));

  // Bad input: named, and nothing written.
  r = Mapctl({"submap", "crop", a_bt_, "--min", "50,50,0", "--max", "60,60,2", "-o",
              dir_.File("none.bt")});
  EXPECT_EQ(r.exit_code, 1) << r.out;
  EXPECT_THAT(r.err, HasSubstr("no known voxel of the map lies in the box"));
  EXPECT_THAT(r.err, HasSubstr("occupied voxels lie within"));
  EXPECT_FALSE(std::filesystem::exists(dir_.File("none.bt")));
  r = Mapctl({"submap", "crop", a_bt_, "--min", "0,0", "--max", "1,1,1", "-o", dir_.File("x.bt")});
  EXPECT_EQ(r.exit_code, 2) << r.out;
  EXPECT_THAT(r.err, HasSubstr("three numbers"));
  r = Mapctl({"submap", "transform", a_bt_, "-o", dir_.File("x.png")});
  EXPECT_EQ(r.exit_code, 2) << r.out;
  EXPECT_THAT(r.err, HasSubstr("must end in .bt or .ot"));
  r = Mapctl({"submap", "transform", a_bt_, "--translate", "1e6,0,0", "-o", dir_.File("x.bt")});
  EXPECT_EQ(r.exit_code, 1) << r.out;
  EXPECT_THAT(r.err, HasSubstr("outside OctoMap's key range"));
  const std::string junk = dir_.File("junk.bt");
  std::ofstream(junk) << "# Octomap OcTree binary file\nres 0.1\nsize 5\ndata\nxx";
  r = Mapctl({"submap", "transform", junk, "-o", dir_.File("x.bt")});
  EXPECT_EQ(r.exit_code, 2) << r.out;
  EXPECT_THAT(r.err, HasSubstr("is not a usable OctoMap file"));
  EXPECT_FALSE(std::filesystem::exists(dir_.File("x.bt")));
}

TEST_F(MapctlSubmapE2eTest, RenderUsageErrors) {
  // Checked before anything is sent or read.
  CommandResult r = Mapctl({"merge", "1", "2", "--render", dir_.File("out.jpg")});
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_THAT(r.err, HasSubstr(".png or .svg"));
  r = RunCommand({MAPCTL_BINARY, "render", a_bt_});
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_THAT(r.err, HasSubstr("-o"));
  r = RunCommand({MAPCTL_BINARY, "render", dir_.File("missing.bt"), "-o", dir_.File("m.png")});
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_THAT(r.err, HasSubstr("missing.bt"));
}

}  // namespace
}  // namespace mapd::testing
