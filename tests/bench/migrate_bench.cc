// `mapd migrate` through real processes (docs/scale-out.md, "Moving a
// map"): a --data-dir mapd fills map site-1 (mapctl simulate), and stops;
// `mapd migrate` copies it into PostgreSQL (fsync on), timed; a mapd on
// PostgreSQL serves it, timed from its start to the first answer equal to
// the source's fused map (rebuilt from the copied observations, since
// snapshots do not move); then the map is migrated back into a directory,
// timed, and served from there.
//
//   migrate_bench [--robots 10] [--scans 2000]
#include <signal.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <string>
#include <thread>
#include <vector>

#include "common/postgres.h"
#include "common/process.h"
#include "common/temp_dir.h"

namespace {

using Clock = std::chrono::steady_clock;
using mapd::testing::CommandResult;
using mapd::testing::MapdProcess;
using mapd::testing::RunCommand;

double Seconds(Clock::duration d) { return std::chrono::duration<double>(d).count(); }

CommandResult Mapctl(const MapdProcess& mapd, std::vector<std::string> args) {
  args.insert(args.begin(), {MAPCTL_BINARY, "--server", mapd.address});
  return RunCommand(args, "", std::chrono::seconds(600));
}

CommandResult Migrate(std::vector<std::string> args, double* seconds) {
  args.insert(args.begin(), {MAPD_BINARY, "migrate"});
  const auto start = Clock::now();
  CommandResult r = RunCommand(args, "", std::chrono::seconds(3600));
  *seconds = Seconds(Clock::now() - start);
  return r;
}

int Fail(const std::string& what, const CommandResult& r) {
  std::fprintf(stderr, "%s failed (exit %d):\n%s%s\n", what.c_str(), r.exit_code, r.out.c_str(),
               r.err.c_str());
  return 1;
}

// `mapctl features --format json` without its map_version line: the live
// server counts a version per group commit, a rebuild one per observation.
std::string FusedMap(const std::string& json) {
  std::string out;
  size_t begin = 0;
  while (begin < json.size()) {
    size_t end = json.find('\n', begin);
    if (end == std::string::npos) end = json.size();
    const std::string line = json.substr(begin, end - begin);
    if (line.find("\"map_version\"") == std::string::npos) out += line + '\n';
    begin = end + 1;
  }
  return out;
}

// Starts mapd with `args` and times it to its first fused map of site-1
// equal to `expected` (FusedMap); -1 if that never comes in 10 minutes.
double TimeToServe(const std::vector<std::string>& args, const std::string& log,
                   const std::string& expected, MapdProcess* mapd) {
  const auto start = Clock::now();
  *mapd =
      mapd::testing::StartMapd("", args, MAPD_BINARY, std::chrono::seconds(600), "serving", log);
  if (mapd->port == 0) return -1;
  CommandResult r;
  while (Seconds(Clock::now() - start) < 600) {
    r = Mapctl(*mapd, {"--map", "site-1", "features", "--format", "json"});
    if (r.exit_code == 0 && FusedMap(r.out) == expected) return Seconds(Clock::now() - start);
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  std::fprintf(stderr, "expected:\n%s\nserved:\n%s%s\n", expected.c_str(), r.out.c_str(),
               r.err.c_str());
  return -1;
}

}  // namespace

int main(int argc, char** argv) {
  std::string robots = "10", scans = "2000";
  for (int i = 1; i + 1 < argc; i += 2) {
    if (std::strcmp(argv[i], "--robots") == 0) robots = argv[i + 1];
    if (std::strcmp(argv[i], "--scans") == 0) scans = argv[i + 1];
  }
  std::string why;
  std::unique_ptr<mapd::testing::PostgresCluster> cluster =
      mapd::testing::PostgresCluster::Start(/*fsync=*/true, &why);
  if (cluster == nullptr) {
    std::fprintf(stderr, "no PostgreSQL: %s\n", why.c_str());
    return 1;
  }
  const std::string store = cluster->NewDatabase();
  mapd::testing::TempDir dir;
  const std::string maps = dir.File("maps"), back = dir.File("back");
  std::filesystem::create_directory(maps);
  std::filesystem::create_directory(back);

  MapdProcess files =
      mapd::testing::StartMapd("", {"--data-dir", maps}, MAPD_BINARY, std::chrono::seconds(60),
                               "serving", dir.File("files.log"));
  if (files.port == 0) return Fail("mapd --data-dir", {});
  CommandResult r = Mapctl(files, {"maps", "create", "site-1"});
  if (r.exit_code != 0) return Fail("maps create", r);
  const auto fill = Clock::now();
  r = Mapctl(files, {"--map", "site-1", "simulate", "--robots", robots, "--scans", scans,
                     "--session", "s1"});
  if (r.exit_code != 0) return Fail("simulate", r);
  std::printf("filled: %s(%.1f s)\n", r.out.c_str(), Seconds(Clock::now() - fill));
  // The source's fused map once its fuser reflects every batch (map_version
  // counts fused batches).
  const std::string all_fused =
      "\"map_version\": " + std::to_string(std::stoll(robots) * std::stoll(scans)) + ",";
  CommandResult expected;
  do {
    expected = Mapctl(files, {"--map", "site-1", "features", "--format", "json"});
    if (expected.exit_code != 0) return Fail("features", expected);
  } while (expected.out.find(all_fused) == std::string::npos);
  mapd::testing::Stop(files.pid, SIGTERM);
  const double file_mb =
      static_cast<double>(std::filesystem::file_size(maps + "/site-1.db")) / (1 << 20);

  double to_pg_s = 0, back_s = 0;
  r = Migrate({"--from", maps + "/site-1.db", "--to", store, "--map", "site-1"}, &to_pg_s);
  if (r.exit_code != 0) return Fail("migrate into PostgreSQL", r);
  std::printf("%s", r.out.c_str());
  MapdProcess pg;
  const double pg_serve_s =
      TimeToServe({"--store", store}, dir.File("pg.log"), FusedMap(expected.out), &pg);
  if (pg_serve_s < 0) return Fail("serving from PostgreSQL: " + pg.log(), {});
  mapd::testing::Stop(pg.pid, SIGTERM);

  r = Migrate({"--from", store, "--from-map", "site-1", "--to", back, "--map", "site-1"}, &back_s);
  if (r.exit_code != 0) return Fail("migrate back", r);
  MapdProcess again;
  const double back_serve_s =
      TimeToServe({"--data-dir", back}, dir.File("back.log"), FusedMap(expected.out), &again);
  if (back_serve_s < 0) return Fail("serving the copy back: " + again.log(), {});
  mapd::testing::Stop(again.pid, SIGTERM);

  std::printf(
      "map: %s robots x %s scans, SQLite file %.1f MiB\n"
      "migrate SQLite -> PostgreSQL: %.1f s; mapd on PostgreSQL start to the same fused map: "
      "%.1f s\n"
      "migrate PostgreSQL -> SQLite: %.1f s; mapd --data-dir start to the same fused map: %.1f s\n",
      robots.c_str(), scans.c_str(), file_mb, to_pg_s, pg_serve_s, back_s, back_serve_s);
  return 0;
}
