// `mapd migrate` as an operator runs it: a map of a --data-dir mapd moves
// into PostgreSQL, is served there as it was, and moves back; a map in use,
// a taken id and a wrong target are refused with the reason.
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <signal.h>

#include <filesystem>
#include <string>
#include <thread>
#include <vector>

#include "common/postgres.h"
#include "common/process.h"
#include "common/temp_dir.h"

namespace mapd::testing {
namespace {

using ::testing::HasSubstr;
using ::testing::Not;

class MigrateE2eTest : public ::testing::Test {
 protected:
  void SetUp() override {
    PostgresCluster* cluster = PostgresCluster::Shared();
    if (cluster == nullptr) GTEST_SKIP() << "no PostgreSQL (install postgresql-15)";
    store_ = cluster->NewDatabase();
  }
  MapdProcess Start(const std::vector<std::string>& args, const std::string& log_name) {
    return StartMapd("", args, MAPD_BINARY, std::chrono::seconds(60), "serving",
                     dir_.File(log_name));
  }
  CommandResult Mapctl(const MapdProcess& mapd, std::vector<std::string> args) {
    args.insert(args.begin(), {MAPCTL_BINARY, "--server", mapd.address});
    return RunCommand(args, "", std::chrono::seconds(120));
  }
  CommandResult Migrate(std::vector<std::string> args) {
    args.insert(args.begin(), {MAPD_BINARY, "migrate"});
    return RunCommand(args, "", std::chrono::seconds(120));
  }
  // site-1's fused map once it reflects all `batches` (map_version counts
  // fused batches; a map served from a copy is rebuilt first).
  std::string FusedMap(const MapdProcess& mapd, int batches) {
    const std::string done = "\"map_version\": " + std::to_string(batches) + ",";
    CommandResult r;
    for (int i = 0; i < 600; ++i) {
      r = Mapctl(mapd, {"--map", "site-1", "features", "--format", "json"});
      if (r.exit_code == 0 && r.out.find(done) != std::string::npos) return r.out;
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
    }
    ADD_FAILURE() << "site-1 never reflected " << batches << " batches: " << r.out << r.err;
    return "";
  }
  std::string Dir(const std::string& name) {
    std::filesystem::create_directory(dir_.File(name));
    return dir_.File(name);
  }

  TempDir dir_;
  std::string store_;
};

TEST_F(MigrateE2eTest, AMapMovesIntoPostgresAndBackAndIsServedAsItWas) {
  const std::string maps = Dir("maps");
  MapdProcess mapd = Start({"--data-dir", maps}, "files.log");
  ASSERT_GT(mapd.port, 0) << mapd.log();
  CommandResult r = Mapctl(mapd, {"maps", "create", "site-1", "--set", "fusion.eta_m=0.25"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  r = Mapctl(mapd,
             {"--map", "site-1", "simulate", "--robots", "2", "--scans", "40", "--session", "s1"});
  ASSERT_EQ(r.exit_code, 0) << r.out << r.err;
  const std::string before = FusedMap(mapd, 80);
  ASSERT_THAT(before, HasSubstr("sim-robot-2"));

  // Served: refused, and nothing is made in the database.
  r = Migrate({"--from", maps + "/site-1.db", "--to", store_, "--map", "site-1"});
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_THAT(r.err, HasSubstr("in use by another mapd"));
  EXPECT_EQ(Stop(mapd.pid, SIGTERM), 0) << mapd.log();

  r = Migrate({"--from", maps + "/site-1.db", "--to", store_, "--map", "site-1"});
  ASSERT_EQ(r.exit_code, 0) << r.out << r.err;
  EXPECT_THAT(r.out, HasSubstr("80 observations (ids kept)"));
  r = Migrate({"--from", maps + "/site-1.db", "--to", store_, "--map", "site-1"});
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_THAT(r.err, HasSubstr("exists in the PostgreSQL database already"));

  // Served from PostgreSQL: the same fused map (rebuilt from the copied
  // observations), its own settings, and a robot's resends are duplicates.
  MapdProcess pg = Start({"--store", store_}, "postgres.log");
  ASSERT_GT(pg.port, 0) << pg.log();
  // Once site-1 is open: listed before as "not serving" while pg opens it
  // (and, before that fix, as "served by" pg's own address).
  r = RunUntil([&] { return Mapctl(pg, {"maps"}); },
               [](const CommandResult& c) {
                 return c.exit_code == 0 && c.out.find("served by") == std::string::npos &&
                        c.out.find("not serving") == std::string::npos;
               });
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_THAT(r.out, HasSubstr("site-1"));
  EXPECT_THAT(r.out, HasSubstr("fusion.eta_m=0.25"));
  EXPECT_EQ(FusedMap(pg, 80), before);
  r = Mapctl(pg,
             {"--map", "site-1", "simulate", "--robots", "2", "--scans", "40", "--session", "s1"});
  ASSERT_EQ(r.exit_code, 0) << r.out << r.err;
  EXPECT_THAT(r.out, HasSubstr("80 duplicate"));
  EXPECT_EQ(Stop(pg.pid, SIGTERM), 0) << pg.log();

  // And back into another directory, settings file included.
  const std::string back = Dir("back");
  r = Migrate({"--from", store_, "--from-map", "site-1", "--to", back, "--map", "site-1"});
  ASSERT_EQ(r.exit_code, 0) << r.out << r.err;
  EXPECT_TRUE(std::filesystem::exists(back + "/site-1.conf"));
  EXPECT_FALSE(std::filesystem::exists(back + "/site-1.db.migrating"));
  MapdProcess files = Start({"--data-dir", back}, "back.log");
  ASSERT_GT(files.port, 0) << files.log();
  EXPECT_EQ(FusedMap(files, 80), before);
  EXPECT_EQ(Stop(files.pid, SIGTERM), 0) << files.log();
}

TEST_F(MigrateE2eTest, BadSourcesAndTargetsAreRefusedWithTheReason) {
  const std::string maps = Dir("maps");
  CommandResult r = Migrate({"--from", maps + "/nothing.db", "--to", store_, "--map", "x"});
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_THAT(r.err, HasSubstr("no database file"));
  EXPECT_FALSE(std::filesystem::exists(maps + "/nothing.db"));

  MapdProcess mapd = Start({"--data-dir", maps}, "files.log");
  ASSERT_GT(mapd.port, 0) << mapd.log();
  ASSERT_EQ(Mapctl(mapd, {"simulate", "--robots", "1", "--scans", "5"}).exit_code, 0);
  EXPECT_EQ(Stop(mapd.pid, SIGTERM), 0) << mapd.log();
  const std::string from = maps + "/default.db";

  r = Migrate({"--from", from, "--to", dir_.File("not-a-map.txt"), "--map", "x"});
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_THAT(r.err, HasSubstr("is none of: a PostgreSQL database"));
  r = Migrate({"--from", from, "--to", store_});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.err, HasSubstr("give --map ID"));
  r = Migrate({"--from", from, "--to", store_, "--map", "../x"});
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_THAT(r.err, HasSubstr("is not a map id"));
  r = Migrate({"--from", from, "--to", maps, "--map", "default"});  // onto itself
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_THAT(r.err, HasSubstr("exists already"));
  r = Migrate({"--from", from, "--to", maps, "--map", "site-9", "--with-tokens"});
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_THAT(r.err, HasSubstr("tokens live in default.db"));
  EXPECT_FALSE(std::filesystem::exists(maps + "/site-9.db"));
  r = Migrate({"--from", from, "--to", "host=/nonexistent dbname=x", "--map", "x"});
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_THAT(r.err, Not(HasSubstr("copied")));

  // Looked for under mapctl: told where it is.
  r = RunCommand({MAPCTL_BINARY, "migrate", "--from", from, "--to", store_, "--map", "x"});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.err, HasSubstr("is `mapd migrate`"));

  // A new single file works, and the source is unchanged.
  r = Migrate({"--from", from, "--to", dir_.File("copy.db")});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_THAT(r.out, HasSubstr("5 observations"));
  r = Migrate({"--from", from, "--to", dir_.File("copy2.db")});
  ASSERT_EQ(r.exit_code, 0) << r.err;
}

}  // namespace
}  // namespace mapd::testing
