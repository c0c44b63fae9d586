// The modes of mapd's files (docs/security.md, "Files"): what it creates is
// the owner's only, and a database or TLS key that others can write is
// refused with the fix.
#include "service/file_modes.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>

#include "common/process.h"
#include "common/temp_dir.h"
#include "service/config.h"
#include "service/server.h"

namespace mapd::testing {
namespace {

using ::testing::HasSubstr;

mode_t ModeOf(const std::string& path) {
  struct stat st {};
  EXPECT_EQ(stat(path.c_str(), &st), 0) << path;
  return st.st_mode & 07777;
}

TEST(FileModesTest, TheDatabaseAndItsWalAndShmAreTheOwnersOnly) {
  TempDir dir;
  const mode_t old_umask = umask(022);  // a typical login shell's, as mapd would inherit
  MapdProcess mapd = StartMapd(dir.File("map.db"));
  umask(old_umask);
  ASSERT_GT(mapd.port, 0) << mapd.log();
  for (const char* f : {"map.db", "map.db-wal", "map.db-shm"}) {
    EXPECT_EQ(ModeOf(dir.File(f)), 0600u) << f;
  }
  EXPECT_EQ(Stop(mapd.pid, SIGTERM), 0);
  EXPECT_THAT(mapd.log(), ::testing::Not(HasSubstr("file_readable_by_others")));
}

TEST(FileModesTest, ADatabaseOthersCanWriteIsRefusedAndLeftAlone) {
  TempDir dir;
  const std::string db = dir.File("map.db");
  ASSERT_EQ(
      RunCommand({MAPD_BINARY, "token", "create", "--db", db, "--role", "admin", "--name", "root"})
          .exit_code,
      0);
  for (const mode_t mode : {0666u, 0620u}) {
    ASSERT_EQ(chmod(db.c_str(), mode), 0);
    CommandResult r = RunCommand({MAPD_BINARY, "--db", db, "--listen", "127.0.0.1:0"});
    EXPECT_EQ(r.exit_code, 1);
    EXPECT_THAT(r.err, HasSubstr("the database '" + db + "' is writable by"));
    EXPECT_THAT(r.err, HasSubstr("admin token offline"));
    EXPECT_THAT(r.err, HasSubstr("chmod 600 '" + db + "'"));
    // The offline token command refuses it too.
    r = RunCommand({MAPD_BINARY, "token", "list", "--db", db});
    EXPECT_EQ(r.exit_code, 1);
    EXPECT_THAT(r.err, HasSubstr("is writable by"));
    EXPECT_EQ(ModeOf(db), mode);
  }
}

TEST(FileModesTest, ADatabaseOthersCanReadIsServedWithAWarning) {
  TempDir dir;
  const std::string db = dir.File("map.db");
  std::ofstream(db).close();  // an empty file is an empty database
  ASSERT_EQ(chmod(db.c_str(), 0644), 0);
  MapdProcess mapd = StartMapd(db);
  ASSERT_GT(mapd.port, 0) << mapd.log();
  EXPECT_EQ(Stop(mapd.pid, SIGTERM), 0);
  EXPECT_THAT(mapd.log(), HasSubstr("event=file_readable_by_others file=" + db));
  EXPECT_THAT(mapd.log(), HasSubstr("mode=0644"));
}

TEST(FileModesTest, ADirectoryAnyoneCanWriteIsRefusedUnlessSticky) {
  TempDir dir;
  const std::string open_dir = dir.File("open");
  std::filesystem::create_directory(open_dir);
  ASSERT_EQ(chmod(open_dir.c_str(), 0777), 0);
  const CommandResult r =
      RunCommand({MAPD_BINARY, "--db", open_dir + "/map.db", "--listen", "127.0.0.1:0"});
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_THAT(r.err, HasSubstr("is writable by everyone (mode 0777) without the sticky bit"));
  EXPECT_FALSE(std::filesystem::exists(open_dir + "/map.db"));
  ASSERT_EQ(chmod(open_dir.c_str(), 01777), 0);  // like /tmp: others cannot replace the file
  EXPECT_TRUE(service::CheckDatabaseFileModes(open_dir + "/map.db").ok());
}

TEST(FileModesTest, TheDefaultPathsDirectoryIsMadeOwnerOnly) {
  TempDir dir;
  const std::string data = dir.File("data/mapd");
  ASSERT_EQ(setenv("MAPD_DATA_DIR", data.c_str(), 1), 0);
  service::ServerConfig config;
  config.listen = "127.0.0.1:0";
  config.shutdown_grace_s = 0.5;
  auto server = service::MapServer::Start(config);
  unsetenv("MAPD_DATA_DIR");
  ASSERT_TRUE(server.ok()) << server.status().ToString();
  EXPECT_EQ(ModeOf(data), 0700u);
  EXPECT_EQ(ModeOf(data + "/map.db"), 0600u);
}

TEST(FileModesTest, ATlsKeyOthersCanWriteIsRefused) {
  TempDir dir;
  const std::string key = dir.File("server.key");
  std::ofstream(key) << "not checked before its mode\n";
  ASSERT_EQ(chmod(key.c_str(), 0646), 0);
  Status s = service::CheckSecretFileMode(key, "tls_key");
  EXPECT_EQ(s.code(), StatusCode::kFailedPrecondition);
  EXPECT_THAT(s.message(), HasSubstr("tls_key '" + key + "' is writable by everyone (mode 0646)"));
  EXPECT_THAT(s.message(), HasSubstr("chmod 600"));

  ASSERT_EQ(chmod(key.c_str(), 0640), 0);  // a group that may read it (Debian's ssl-cert)
  ::testing::internal::CaptureStderr();
  EXPECT_TRUE(service::CheckSecretFileMode(key, "tls_key").ok());
  EXPECT_THAT(::testing::internal::GetCapturedStderr(),
              HasSubstr("event=file_readable_by_others file=" + key + " what=tls_key mode=0640"));
}

}  // namespace
}  // namespace mapd::testing
