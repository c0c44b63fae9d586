#include "service/config.h"

#include <fstream>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "common/temp_dir.h"

namespace mapd::service {
namespace {

using ::testing::HasSubstr;

Status Parse(std::vector<std::string> args, ServerConfig* c) {
  bool help = false;
  return ParseFlags(args, c, &help);
}

TEST(ConfigTest, DefaultsAreValidAndLoopback) {
  ServerConfig c;
  EXPECT_TRUE(c.Validate().ok());
  EXPECT_EQ(c.listen, "127.0.0.1:50051");
}

TEST(ConfigTest, FlagsOverrideTheConfigFileWhateverTheirOrder) {
  mapd::testing::TempDir dir;
  std::ofstream(dir.File("mapd.conf")) << "# comment\nfusion.gamma = 0.5\nfusion.eta_m=0.2\nsync = full\n";
  ServerConfig c;
  ASSERT_TRUE(Parse({"--fusion.gamma=0.4", "--config", dir.File("mapd.conf")}, &c).ok());
  EXPECT_DOUBLE_EQ(c.fusion.gamma, 0.4);
  EXPECT_DOUBLE_EQ(c.fusion.eta_m, 0.2);
  EXPECT_TRUE(c.sync_full);
}

TEST(ConfigTest, BadValuesAreNamed) {
  ServerConfig c;
  EXPECT_THAT(Parse({"--fusion.gamma", "2"}, &c).message(), HasSubstr("gamma"));
  ServerConfig d;
  EXPECT_THAT(Parse({"--fusion.eta_m=abc"}, &d).message(), HasSubstr("fusion.eta_m"));
  ServerConfig e;
  EXPECT_THAT(Parse({"--no-such-thing=1"}, &e).message(), HasSubstr("unknown setting 'no-such-thing'"));
  ServerConfig f;
  EXPECT_THAT(Parse({"--db"}, &f).message(), HasSubstr("needs a value"));
}

TEST(ConfigTest, ConfigFileErrorsNameTheLine) {
  mapd::testing::TempDir dir;
  std::ofstream(dir.File("bad.conf")) << "listen = 127.0.0.1:1\nthis line has no equals sign\n";
  ServerConfig c;
  EXPECT_THAT(Parse({"--config", dir.File("bad.conf")}, &c).message(), HasSubstr("bad.conf:2"));
}

TEST(ConfigTest, RemoteListenNeedsTlsOrAnExplicitOptOut) {
  ServerConfig c;
  EXPECT_THAT(Parse({"--listen", "0.0.0.0:50051"}, &c).message(), HasSubstr("tls_cert"));
  ServerConfig d;
  EXPECT_TRUE(Parse({"--listen", "0.0.0.0:50051", "--allow_insecure_remote", "true"}, &d).ok());
}

}  // namespace
}  // namespace mapd::service
