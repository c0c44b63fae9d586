// mapctl against the real mapd: a server on a free loopback port with a
// temporary database, driven through the command line as a script would.
#include <fcntl.h>
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <sqlite3.h>
#include <unistd.h>

#include <Eigen/Core>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <string>
#include <thread>
#include <vector>

#include "client/support/svg_facts.h"
#include "common/process.h"
#include "common/temp_dir.h"

namespace mapd::testing {
namespace {

using ::testing::HasSubstr;
using ::testing::Not;

class MapctlE2eTest : public ::testing::Test {
 protected:
  void SetUp() override {
    // Each export below reads the map once, and they are compared with each
    // other: a read must wait until the fuser holds every scan just sent. Under
    // ASan that can take longer than the default limits.read_wait_s (5 s).
    mapd_ = StartMapd(dir_.File("map.db"), {"--limits.read_wait_s", "120"}, MAPD_BINARY);
    ASSERT_GT(mapd_.port, 0) << "mapd did not come up:\n" << mapd_.log();
  }
  void TearDown() override {
    if (mapd_.pid > 0) Stop(mapd_.pid, SIGKILL);
  }

  CommandResult Mapctl(std::vector<std::string> args, const std::string& stdin_data = "") {
    args.insert(args.begin(), {MAPCTL_BINARY, "--server", mapd_.address});
    return RunCommand(args, stdin_data);
  }

  static size_t FileSize(const std::string& path) {
    std::error_code ec;
    const auto size = std::filesystem::file_size(path, ec);
    return ec ? 0 : static_cast<size_t>(size);
  }
  static size_t Count(const std::string& text, const std::string& needle) {
    size_t n = 0;
    for (size_t at = text.find(needle); at != std::string::npos; at = text.find(needle, at + 1))
      ++n;
    return n;
  }

  TempDir dir_;
  MapdProcess mapd_;
};

TEST_F(MapctlE2eTest, ScriptedSession) {
  // Two simulated robots stream 60 scans each.
  CommandResult r = Mapctl({"simulate", "--robots", "2", "--scans", "60", "--session", "e2e"});
  ASSERT_EQ(r.exit_code, 0) << r.out << r.err;
  EXPECT_THAT(r.out, HasSubstr("120 stored"));

  r = Mapctl({"status", "--json"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_THAT(r.out, HasSubstr("\"batches\": 120"));  // 64-bit integers are numbers
  EXPECT_THAT(r.out, HasSubstr("\"robots\": 2"));

  r = Mapctl({"robots"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_THAT(r.out, HasSubstr("sim-robot-1"));
  EXPECT_THAT(r.out, HasSubstr("sim-robot-2"));

  // Exports, format from the extension.
  const std::string geojson = dir_.File("map.geojson"), svg = dir_.File("map.svg");
  r = Mapctl({"features", "-o", geojson});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  r = Mapctl({"features", "-o", svg});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  ASSERT_GT(FileSize(geojson), 0u);
  ASSERT_GT(FileSize(svg), 0u);
  std::ifstream g(geojson), s(svg);
  const std::string geojson_text((std::istreambuf_iterator<char>(g)),
                                 std::istreambuf_iterator<char>());
  const std::string svg_text((std::istreambuf_iterator<char>(s)), std::istreambuf_iterator<char>());
  EXPECT_THAT(geojson_text, HasSubstr("FeatureCollection"));
  EXPECT_GT(Count(geojson_text, "\"LineString\""), 3u);
  // One cairo stroke per feature in its kind's colour, plus one legend sample per kind.
  const size_t strokes = testing::CountShapesOfColour(svg_text, "#1f77b4") +
                         testing::CountShapesOfColour(svg_text, "#d62728") - 2;
  EXPECT_GT(strokes, 3u);
  EXPECT_EQ(Count(geojson_text, "\"LineString\""), strokes);

  // Re-sending the same session is answered duplicate, and exits 0.
  r = Mapctl({"simulate", "--robots", "1", "--scans", "5", "--session", "e2e"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_THAT(r.out, HasSubstr("5 duplicate"));

  // SIGTERM: the server drains, checkpoints and exits 0.
  EXPECT_EQ(Stop(mapd_.pid, SIGTERM), 0) << mapd_.log();
  mapd_.pid = -1;
}

// mapd --data-dir: maps made and listed from mapctl, each its own map.
TEST(MapctlMapsE2eTest, SeveralMapsFromTheCommandLine) {
  TempDir dir;
  std::filesystem::create_directory(dir.File("maps"));
  MapdProcess mapd = StartMapd("", {"--data-dir", dir.File("maps")}, MAPD_BINARY,
                               std::chrono::seconds(30), "serving", dir.File("mapd.log"));
  ASSERT_GT(mapd.port, 0) << mapd.log();
  auto mapctl = [&](std::vector<std::string> args) {
    args.insert(args.begin(), {MAPCTL_BINARY, "--server", mapd.address});
    return RunCommand(args);
  };
  CommandResult r = mapctl({"maps", "create", "site-1", "--set", "fusion.eta_m=0.25"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_THAT(r.out, HasSubstr("created map site-1"));
  r = mapctl({"maps", "create", "site-2", "--set", "limits.max_streams=5"});
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_THAT(r.err, HasSubstr("is not a map's setting"));
  r = mapctl({"--map", "site-1", "simulate", "--robots", "2", "--scans", "40"});
  ASSERT_EQ(r.exit_code, 0) << r.out << r.err;
  EXPECT_THAT(r.out, HasSubstr("80 stored"));

  r = mapctl({"maps"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_THAT(r.out, HasSubstr("default"));
  EXPECT_THAT(r.out, HasSubstr("site-1"));
  EXPECT_THAT(r.out, HasSubstr("fusion.eta_m=0.25"));
  EXPECT_THAT(r.out, Not(HasSubstr("site-2")));
  setenv("MAPD_MAP", "site-1", 1);  // mapctl inherits it
  r = mapctl({"status", "--json"});
  unsetenv("MAPD_MAP");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_THAT(r.out, HasSubstr("\"batches\": 80"));
  r = mapctl({"status", "--json"});  // no map: the default one, empty
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_THAT(r.out, Not(HasSubstr("\"batches\": 80")));
  r = mapctl({"--map", "site-1", "features", "--format", "json"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_THAT(r.out, HasSubstr("sim-robot-1"));

  // A map the server does not serve: exit 1, naming the maps it has.
  r = mapctl({"--map", "site-2", "features"});
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_THAT(r.err, HasSubstr("does not serve map 'site-2'; it serves: default, site-1"));
  r = mapctl({"maps", "create", "site-1"});
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_THAT(r.err, HasSubstr("ALREADY_EXISTS"));
  Stop(mapd.pid, SIGTERM);
}

TEST_F(MapctlE2eTest, TrailsAsGeoJson) {
  CommandResult r = Mapctl({"simulate", "--robots", "2", "--scans", "30", "--session", "walk"});
  ASSERT_EQ(r.exit_code, 0) << r.out << r.err;
  const std::string path = dir_.File("trails.geojson");
  r = Mapctl({"trails", "-o", path});
  ASSERT_EQ(r.exit_code, 0) << r.out << r.err;
  EXPECT_THAT(r.out, HasSubstr("wrote 2 session trails (0 not tied"));
  std::ifstream in(path);
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_THAT(text, HasSubstr("\"FeatureCollection\""));
  EXPECT_EQ(Count(text, "\"LineString\""), 2u) << text.substr(0, 2000);
  EXPECT_THAT(text, HasSubstr("\"robot_id\": \"sim-robot-1\""));
  EXPECT_THAT(text, HasSubstr("\"robot_id\": \"sim-robot-2\""));
  EXPECT_THAT(text, HasSubstr("\"session_id\": \"walk\""));
  EXPECT_THAT(text, HasSubstr("\"frame\": \"map\""));
  EXPECT_THAT(text, HasSubstr("\"poses\": 30"));

  // One robot, thinned, on stdout.
  r = Mapctl({"trails", "--robot", "sim-robot-2", "--max-poses", "5"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(Count(r.out, "\"LineString\""), 1u);
  EXPECT_THAT(r.out, HasSubstr("\"poses\": 5"));
  EXPECT_THAT(r.out, HasSubstr("\"stored_poses\": 30"));
  r = Mapctl({"trails", "--robot", "bad robot"});
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_THAT(r.err, HasSubstr("INVALID_ARGUMENT"));
}

TEST_F(MapctlE2eTest, IngestReportsTheRejectedLine) {
  // Three batches as JSON lines; the second gets a NaN coordinate.
  const std::string jsonl = dir_.File("batches.jsonl");
  CommandResult r =
      Mapctl({"simulate", "--robots", "1", "--scans", "3", "--session", "file", "--export", jsonl});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  std::ifstream in(jsonl);
  std::vector<std::string> lines;
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  ASSERT_EQ(lines.size(), 3u);
  // The .proto field names, like `status --json` (not protobuf's camelCase).
  EXPECT_THAT(lines[0], HasSubstr("\"robot_id\":\"sim-robot-1\""));
  EXPECT_THAT(lines[0], HasSubstr("\"session_id\":\"file\""));
  const std::string key = "\"translation\":{\"x\":";
  const size_t at = lines[1].find(key);
  ASSERT_NE(at, std::string::npos) << lines[1];
  const size_t value_end = lines[1].find_first_of(",}", at + key.size());
  lines[1].replace(at + key.size(), value_end - at - key.size(), "\"NaN\"");
  std::string text;
  for (const std::string& line : lines) text += line + "\n";

  r = Mapctl({"ingest", "-"}, text);
  EXPECT_EQ(r.exit_code, 1) << r.out << r.err;
  EXPECT_THAT(r.out, HasSubstr("2 stored"));
  EXPECT_THAT(r.out, HasSubstr("1 rejected"));
  EXPECT_THAT(r.err, HasSubstr("line 2"));
  EXPECT_THAT(r.err, HasSubstr("NaN"));
  EXPECT_THAT(r.err, HasSubstr("INVALID_ARGUMENT"));

  // A line that is not an ObservationBatch is named by its number.
  r = Mapctl({"ingest", "-"}, lines[0] + "\n{\"robotId\": 12, \"nope\": true}\n");
  EXPECT_EQ(r.exit_code, 2) << r.out << r.err;
  EXPECT_THAT(r.err, HasSubstr("line 2"));
}

// A recorded robot through the robot library: a CARMEN log of a corridor
// (walls at y = +-1.5 m, 180 beams, 40 scans 0.2 m apart) streamed as that
// robot, its walls fused; again is all duplicates; a malformed log sends nothing.
TEST_F(MapctlE2eTest, ReplayStreamsARecordedRobot) {
  std::string log = "# a CARMEN log\nODOM 0 0 0 0 0 0 0 host 0\n";
  for (int k = 0; k < 40; ++k) {
    log += "FLASER 180";
    for (int i = 0; i < 180; ++i) {
      const double s = std::sin(-M_PI / 2 + i * M_PI / 180);
      log += " " + std::to_string(std::abs(s) < 1.5 / 80 ? 80.0 : 1.5 / std::abs(s));
    }
    const double x = 0.2 * k, t = 1700000000.0 + 0.1 * k;
    log += " " + std::to_string(x) + " 0 0 " + std::to_string(x) + " 0 0 " + std::to_string(t) +
           " host " + std::to_string(t) + "\n";
  }
  const std::string path = dir_.File("corridor.log");
  std::ofstream(path) << log;

  CommandResult r = Mapctl({"replay", "--session", "rec", path});
  ASSERT_EQ(r.exit_code, 0) << r.out << r.err;
  EXPECT_THAT(r.out, HasSubstr("1 robot, 40 scans"));
  EXPECT_THAT(r.out, HasSubstr("40 batches sent: 40 stored"));
  r = Mapctl({"robots"});
  EXPECT_THAT(r.out, HasSubstr("corridor"));  // named by its file
  r = Mapctl({"features", "--format", "json"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(Count(r.out, "\"id\""), 2U) << r.out;  // one fused feature per wall

  r = Mapctl({"replay", "--session", "rec", path});
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_THAT(r.out, HasSubstr("40 duplicate"));

  const std::string bad = dir_.File("bad.log");
  std::size_t cut = 0;  // after the 12th line: 10 scans
  for (int line = 0; line < 12; ++line) cut = log.find('\n', cut) + 1;
  std::ofstream(bad) << log.substr(0, cut) << "FLASER 180 1.0 2.0\n" << log.substr(cut);
  r = Mapctl({"replay", "--session", "bad", "--robot-id", "other", bad});
  EXPECT_EQ(r.exit_code, 2) << r.out << r.err;
  EXPECT_THAT(r.err, HasSubstr("bad.log:13"));
  EXPECT_THAT(r.err, HasSubstr("missing range"));
  r = Mapctl({"robots"});
  EXPECT_THAT(r.out, ::testing::Not(HasSubstr("other")));  // nothing was sent
}

#ifdef MAPD_HAVE_ROBOT_PLANES
// A 3D corridor scanned from a sensor driving along it: walls y = +-2 m
// (0..3 m high) and the floor z = 0, sampled every 10 cm within 6 m, in the
// sensor frame (no rotation), one .xyz file a scan.
std::string CorridorScan(const Eigen::Vector3d& sensor) {
  std::string text;
  const auto add = [&](const Eigen::Vector3d& p) {
    if ((p - sensor).norm() > 6.0) return;
    const Eigen::Vector3d q = p - sensor;
    text +=
        std::to_string(q.x()) + " " + std::to_string(q.y()) + " " + std::to_string(q.z()) + "\n";
  };
  for (int i = -60; i <= 160; ++i) {
    const double x = 0.1 * i;
    for (int k = 0; k <= 30; ++k) {
      add({x, -2.0, 0.1 * k});
      add({x, 2.0, 0.1 * k});
    }
    for (int j = -19; j <= 19; ++j) add({x, 0.1 * j, 0.0});
  }
  return text;
}

// Folders of 3D scans through the robot library: scans named by their times
// with a TUM trajectory (nearest pose in time, a scan without one skipped), and
// the same corridor with KITTI poses (by order, the camera's y-down world
// turned z up); planes fused into two walls and a floor; a folder without poses, poses
// that do not match and a malformed scan send nothing.
TEST_F(MapctlE2eTest, ReplayStreamsFoldersOf3dScans) {
  namespace fs = std::filesystem;
  const std::string tum = dir_.File("tum"), kitti = dir_.File("kitti");
  fs::create_directories(tum);
  fs::create_directories(kitti);
  std::string tum_poses = "# timestamp tx ty tz qx qy qz qw\n", kitti_poses;
  for (int k = 0; k < 5; ++k) {
    const Eigen::Vector3d sensor(1.0 * k, 0.3, 1.2);
    const std::string stamp = std::to_string(1700000000 + k) + ".5";
    std::ofstream(tum + "/" + stamp + ".xyz") << CorridorScan(sensor);
    tum_poses +=
        std::to_string(1700000000 + k) + ".52 " + std::to_string(sensor.x()) + " 0.3 1.2 0 0 0 1\n";
    char name[16];
    std::snprintf(name, sizeof name, "%06d.xyz", k);
    std::ofstream(kitti + "/" + name) << CorridorScan(sensor);
    // The camera world: x right (map -y), y down (map -z), z forward (map x).
    char line[256];
    std::snprintf(line, sizeof line, "1 0 0 %f 0 1 0 %f 0 0 1 %f\n", -sensor.y(), -sensor.z(),
                  sensor.x());
    kitti_poses += line;
  }
  std::ofstream(tum + "/1700000100.0.xyz") << CorridorScan({0, 0, 1});  // no pose near it
  std::ofstream(tum + "/poses.txt") << tum_poses;                       // found without --poses
  const std::string kitti_file = dir_.File("00.txt");
  std::ofstream(kitti_file) << kitti_poses;

  CommandResult r =
      Mapctl({"replay", "--session", "s3", "--poses", kitti_file, kitti, "--export", "-"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(Count(r.out, "\n"), 5U);
  // KITTI scans 0.1 s apart; the third one's sensor is at x = 2 m in the map frame.
  EXPECT_THAT(r.out, HasSubstr("\"translation\":{\"x\":2,\"y\":0.3"));
  EXPECT_THAT(r.out, HasSubstr("\"planes\""));
  r = Mapctl({"replay", "--session", "s3", tum});
  ASSERT_EQ(r.exit_code, 0) << r.out << r.err;
  EXPECT_THAT(r.out, HasSubstr("1 robot, 5 scans"));
  EXPECT_THAT(r.out, HasSubstr("planes"));
  EXPECT_THAT(r.out, HasSubstr("5 stored"));
  EXPECT_THAT(r.err, HasSubstr("1 scans without a pose within 0.050 s, skipped"));
  r = Mapctl({"features", "--format", "json"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_THAT(r.out, HasSubstr("\"total\": 2"));       // one fused wall a side
  EXPECT_EQ(Count(r.out, "\"normal\""), 1U) << r.out;  // and the floor
  r = Mapctl({"robots"});
  EXPECT_THAT(r.out, HasSubstr("tum"));

  // Numbered scans with a TUM file: no name is a pose's time, so by order.
  const std::string numbered = dir_.File("numbered");
  fs::create_directories(numbered);
  for (int k = 0; k < 5; ++k) {
    std::filesystem::copy_file(kitti + "/00000" + std::to_string(k) + ".xyz",
                               numbered + "/00000" + std::to_string(k) + ".xyz");
  }
  std::ofstream(numbered + "/poses.txt") << tum_poses;
  r = Mapctl({"replay", numbered, "--export", "-"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(Count(r.out, "\n"), 5U);
  EXPECT_THAT(r.out, HasSubstr("\"translation\":{\"x\":2,\"y\":0.3"));

  const std::string bare = dir_.File("bare");
  fs::create_directories(bare);
  std::ofstream(bare + "/a.xyz") << "1 2 3\n";
  r = Mapctl({"replay", bare});
  EXPECT_EQ(r.exit_code, 2) << r.out << r.err;
  EXPECT_THAT(r.err, HasSubstr("needs its poses: --poses FILE"));
  r = Mapctl({"replay", "--poses", kitti_file, bare});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.err, HasSubstr("has 5 poses for 1 scans"));
  r = Mapctl({"replay", "--poses", kitti_file, "--poses", kitti_file, bare});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.err, HasSubstr("2 --poses files for 1 scan folders"));
  std::ofstream(kitti + "/000002.xyz") << "1 2 3\n4 5\n";
  r = Mapctl({"replay", "--session", "bad", "--robot-id", "other", "--poses", kitti_file, kitti});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.err, HasSubstr("000002.xyz:2: not an 'x y z' line"));
  r = Mapctl({"robots"});
  EXPECT_THAT(r.out, ::testing::Not(HasSubstr("other")));  // nothing was sent
}
#endif  // MAPD_HAVE_ROBOT_PLANES

TEST_F(MapctlE2eTest, ExitCodesForScripts) {
  CommandResult r = Mapctl({"features", "--bbox", "1,2"});
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_THAT(r.err, HasSubstr("--bbox"));

  r = Mapctl({"no-such-command"});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.err, HasSubstr("unknown command 'no-such-command'"));

  // Bad flags: one line naming the flag, exit 2, before any server call.
  for (const std::vector<std::string>& args : std::vector<std::vector<std::string>>{
           {"features", "--kind", "wall"},
           {"simulate", "--robots", "0"},
           {"features", "--bogus"},
           {"render", "a.bt", "-o", "a.png", "--max-size", "8"}}) {
    r = Mapctl(args);
    EXPECT_EQ(r.exit_code, 2) << args[1];
    EXPECT_THAT(r.err, HasSubstr(args[1] == "--bogus" ? "--bogus" : args[args.size() - 2]))
        << r.err;
    EXPECT_EQ(Count(r.err, "\n"), 1u) << r.err;
  }
  // A flag given twice: the later one wins, as before CLI11.
  r = Mapctl({"simulate", "--robots", "1", "--scans", "5", "--scans", "2", "--export", "-"});
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(Count(r.out, "\n"), 2u);
  // --help shows the defaults the code uses.
  r = Mapctl({"simulate", "--help"});
  EXPECT_EQ(r.exit_code, 0);
  EXPECT_THAT(r.out, HasSubstr("--scans UINT"));
  EXPECT_THAT(r.out, HasSubstr("=100"));

  r = RunCommand({MAPCTL_BINARY, "--server", "127.0.0.1:1", "status"});
  EXPECT_EQ(r.exit_code, 3) << r.err;
  EXPECT_THAT(r.err, HasSubstr("UNAVAILABLE"));
  EXPECT_EQ(Count(r.err, "\n"), 1u) << "one line: " << r.err;

  // A merge of submaps that do not exist: one readable line naming the id, exit 1.
  r = Mapctl({"merge", "1", "2", "--wait"});
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_THAT(r.err, AnyOf(HasSubstr("(NOT_FOUND)"), HasSubstr("(UNIMPLEMENTED)")));
  EXPECT_EQ(Count(r.err, "\n"), 1u) << r.err;

  r = Mapctl({"features", "--help"});
  EXPECT_EQ(r.exit_code, 0);
  EXPECT_THAT(r.out, HasSubstr("--bbox"));
}

TEST_F(MapctlE2eTest, ServerExitsCleanlyOnSigterm) {
  CommandResult r = Mapctl({"simulate", "--robots", "2", "--scans", "20"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(Stop(mapd_.pid, SIGTERM), 0) << mapd_.log();
  mapd_.pid = -1;
}

// Input mistakes are one line on stderr and exit 2 (issue 43 item 10), before
// anything is sent or written.
TEST_F(MapctlE2eTest, InputMistakesAreUsageErrors) {
  const auto expect_usage = [](const CommandResult& r, const std::string& says) {
    EXPECT_EQ(r.exit_code, 2) << r.out << r.err;
    EXPECT_THAT(r.err, HasSubstr(says));
    EXPECT_EQ(Count(r.err, "\n"), 1u) << r.err;
  };
  // A server address without a port was a connection error after the timeout.
  expect_usage(RunCommand({MAPCTL_BINARY, "--server", "127.0.0.1", "status"}), "HOST:PORT");
  expect_usage(RunCommand({MAPCTL_BINARY, "--server", "127.0.0.1:99999", "status"}), "1..65535");
  // An unknown command with --help printed the top-level help and exited 0.
  expect_usage(RunCommand({MAPCTL_BINARY, "nonsense", "--help"}), "unknown command 'nonsense'");
  expect_usage(RunCommand({MAPCTL_BINARY, "--server", mapd_.address, "--timeout", "5", "nonsense",
                           "--help"}),
               "unknown command 'nonsense'");
  // features -o out.xyz wrote a table into out.xyz.
  const std::string xyz = dir_.File("out.xyz");
  expect_usage(Mapctl({"features", "-o", xyz}), "--format");
  EXPECT_FALSE(std::filesystem::exists(xyz));
  EXPECT_EQ(Mapctl({"features", "-o", dir_.File("out.txt")}).exit_code, 0);
  EXPECT_EQ(Mapctl({"features", "-o", xyz, "--format", "json"}).exit_code, 0);
  // The world change of simulate.
  expect_usage(Mapctl({"simulate", "--remove-wall", "12"}), "walls 0..11");
  expect_usage(Mapctl({"simulate", "--add-wall", "1,2,3"}), "X0,Y0,X1,Y1");
  expect_usage(Mapctl({"simulate", "--add-wall", "1,2,1,2"}), "X0,Y0,X1,Y1");
  // --version, and --help of a real command, still exit 0.
  const CommandResult version = RunCommand({MAPCTL_BINARY, "--version"});
  EXPECT_EQ(version.exit_code, 0);
  EXPECT_THAT(version.out, HasSubstr("mapctl " MAPD_VERSION_FOR_TESTS));
  EXPECT_EQ(RunCommand({MAPCTL_BINARY, "features", "--help"}).exit_code, 0);
}

}  // namespace
}  // namespace mapd::testing

namespace mapd::testing {
namespace {

// Writes an audit row as it is, as an older mapd (which did not escape) or
// another tool could have: mapctl must still show it on one line.
void InsertRawAuditRow(const std::string& db, const std::string& target) {
  sqlite3* conn = nullptr;
  ASSERT_EQ(sqlite3_open_v2(db.c_str(), &conn, SQLITE_OPEN_READWRITE, nullptr), SQLITE_OK);
  sqlite3_busy_timeout(conn, 10000);
  sqlite3_stmt* stmt = nullptr;
  ASSERT_EQ(sqlite3_prepare_v2(conn,
                               "INSERT INTO audit_log (time_ns, who, role, action, target, "
                               "result) VALUES (1, 'old', 'robot', 'Ingest', ?1, 'ok')",
                               -1, &stmt, nullptr),
            SQLITE_OK);
  sqlite3_bind_text(stmt, 1, target.data(), static_cast<int>(target.size()), SQLITE_TRANSIENT);
  EXPECT_EQ(sqlite3_step(stmt), SQLITE_DONE) << sqlite3_errmsg(conn);
  sqlite3_finalize(stmt);
  sqlite3_close(conn);
}

// Bootstrap as docs/security.md describes it: the first admin token from the
// database file, then everything else through mapctl with tokens.
TEST_F(MapctlE2eTest, TokensRolesAndAuditEndToEnd) {
  CommandResult r = RunCommand({MAPD_BINARY, "token", "create", "--db", dir_.File("map.db"),
                                "--role", "admin", "--name", "root"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::string admin = r.out.substr(0, r.out.find('\n'));
  ASSERT_EQ(admin.rfind("mapd_", 0), 0u) << r.out;

  r = Mapctl({"status"});  // a token exists now: no anonymous calls
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_THAT(r.err, HasSubstr("UNAUTHENTICATED"));

  r = Mapctl({"--token", admin, "token", "create", "--name", "r1-key", "--role", "robot", "--robot",
              "r1"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::string robot = r.out.substr(0, r.out.find('\n'));
  r = Mapctl({"--token", robot, "whoami"});
  EXPECT_THAT(r.out, HasSubstr("r1-key (role robot, robot r1)"));

  // The robot streams as itself; as anyone else it is refused (exit 1).
  r = Mapctl({"--token", robot, "simulate", "--robots", "1", "--robot-id", "r1", "--scans", "20"});
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_THAT(r.out, HasSubstr("20 stored"));
  r = Mapctl({"--token", robot, "simulate", "--robots", "1", "--scans", "5"});
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_THAT(r.err, HasSubstr("PERMISSION_DENIED"));
  r = Mapctl({"--token", robot, "audit"});
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_THAT(r.err, HasSubstr("read_audit"));

  r = Mapctl({"--token", admin, "token", "list"});
  EXPECT_THAT(r.out, HasSubstr("r1-key"));
  r = Mapctl({"--token", admin, "token", "revoke", "2"});
  EXPECT_EQ(r.exit_code, 0) << r.err;
  r = Mapctl({"--token", robot, "status"});
  EXPECT_THAT(r.err, HasSubstr("revoked"));

  r = Mapctl({"--token", admin, "audit", "--limit", "10"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_THAT(r.out, HasSubstr("RevokeToken"));
  EXPECT_THAT(r.out, HasSubstr("r1-key"));
  EXPECT_THAT(r.out, HasSubstr("denied"));
  EXPECT_THAT(r.out, HasSubstr("mapd token (offline)"));
  EXPECT_THAT(r.out, HasSubstr("database file"));     // how the offline admin proved it
  EXPECT_THAT(r.out, HasSubstr("token 127.0.0.1:"));  // and the API's calls: how and from where

  // A row holding a newline and terminal escapes (issue 43) is one line,
  // its control characters shown, not sent to the terminal.
  InsertRawAuditRow(dir_.File("map.db"),
                    "robot r2\n9 2026-12-04T10:00:00Z root admin RevokeToken x ok\x1b[8m");
  r = Mapctl({"--token", admin, "audit", "--limit", "1"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_THAT(r.out, HasSubstr("robot r2\\n9 2026-12-04T10:00:00Z root admin RevokeToken x "
                               "ok\\x1b[8m"));
  EXPECT_EQ(std::count(r.out.begin(), r.out.end(), '\n'), 2) << r.out;  // header + 1 row
  EXPECT_EQ(r.out.find('\x1b'), std::string::npos);
  // For scripts: JSON, its strings escaped by JSON's rules, ids as numbers.
  r = Mapctl({"--token", admin, "audit", "--limit", "1", "--json"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_THAT(r.out, HasSubstr("\"entries\": ["));
  EXPECT_THAT(r.out, HasSubstr("robot r2\\n9 2026-12-04T10:00:00Z"));
  EXPECT_THAT(r.out, ::testing::ContainsRegex("\"id\": [0-9]+,"));
  EXPECT_EQ(r.out.find('\x1b'), std::string::npos);
}

// Reads `path` until `pred` holds on its text (bounded: a bug fails, never hangs).
bool WaitForText(const std::string& path, const std::function<bool(const std::string&)>& pred) {
  for (int i = 0; i < 600; ++i) {
    std::ifstream in(path);
    const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    if (pred(text)) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  return false;
}

TEST_F(MapctlE2eTest, WatchPrintsChangesLiveReconnectsAndEndsCleanlyOnCtrlC) {
  const std::string out = dir_.File("watch.jsonl"), err = dir_.File("watch.err");
  const int out_fd = open(out.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0600);
  const int err_fd = open(err.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0600);
  const pid_t watch = internal::Spawn({MAPCTL_BINARY, "--server", mapd_.address, "watch", "--json"},
                                      -1, out_fd, err_fd);
  close(out_fd);
  close(err_fd);
  ASSERT_GT(watch, 0);
  ASSERT_TRUE(WaitForText(out, [](const std::string& t) { return !t.empty(); }));
  CommandResult r = Mapctl({"simulate", "--robots", "1", "--scans", "30", "--session", "w"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  ASSERT_TRUE(WaitForText(out, [](const std::string& t) {
    return t.find("\"change\":\"added\"") != std::string::npos;
  })) << internal::ReadFile(err);
  // A second pass over the same walls updates them.
  r = Mapctl({"simulate", "--robots", "1", "--scans", "10", "--session", "w2"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  ASSERT_TRUE(WaitForText(out, [](const std::string& t) {
    return t.find("\"change\":\"updated\"") != std::string::npos;
  })) << internal::ReadFile(err);

  // The server stops: the watch says so and keeps trying.
  EXPECT_EQ(Stop(mapd_.pid, SIGTERM), 0) << mapd_.log();
  mapd_.pid = -1;
  EXPECT_TRUE(WaitForText(
      err, [](const std::string& t) { return t.find("reconnecting") != std::string::npos; }));
  EXPECT_EQ(Stop(watch, SIGINT), 0) << "Ctrl-C ends the watch cleanly";

  std::ifstream in(out);
  std::vector<std::string> lines;
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  ASSERT_GT(lines.size(), 2u);
  EXPECT_THAT(lines[0], HasSubstr("\"change\":\"resync\""));
  size_t added = 0;
  for (const std::string& line : lines) {
    EXPECT_EQ(line.rfind("{\"map_version\":", 0), 0u) << line;
    if (line.find("\"change\":\"added\"") != std::string::npos) {
      ++added;
      EXPECT_THAT(line, HasSubstr("\"member_count\":"));
      EXPECT_THAT(line, HasSubstr("\"robots\":[\"sim-robot-1\"]"));
    }
  }
  EXPECT_GT(added, 3u);
  EXPECT_THAT(internal::ReadFile(err), HasSubstr("since_map_version="));
}

}  // namespace
}  // namespace mapd::testing
