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

TEST(ConfigTest, SubmapAndMergeSettingsParseAndAreValidated) {
  ServerConfig c;
  ASSERT_TRUE(Parse({"--limits.max_submap_bytes", "1048576", "--limits.max_concurrent_merges=2",
                     "--limits.max_queued_merges=0", "--merge.min_matched_corners=6",
                     "--merge.max_residual_voxels=1.5", "--merge.min_overlap_score=0.5", "--merge.max_seconds=10",
                     "--merge.resolution_policy=resample", "--merge.fusion_rule=log_odds"},
                    &c)
                  .ok());
  EXPECT_EQ(c.submaps.max_submap_bytes, 1048576u);
  EXPECT_EQ(c.submaps.max_concurrent_merges, 2u);
  EXPECT_EQ(c.submaps.max_queued_merges, 0u);
  EXPECT_EQ(c.submaps.min_matched_corners, 6);
  EXPECT_EQ(c.submaps.max_residual_voxels, 1.5);
  EXPECT_EQ(c.submaps.min_overlap_score, 0.5);
  EXPECT_EQ(c.submaps.max_merge_seconds, 10.0);
  EXPECT_TRUE(c.submaps.resample_resolutions);
  EXPECT_TRUE(c.submaps.log_odds_fusion);

  const std::vector<std::pair<std::string, std::string>> bad = {
      {"--limits.max_concurrent_merges=0", "limits.max_concurrent_merges"},
      {"--limits.max_submap_bytes=10", "limits.max_submap_bytes"},
      {"--merge.min_matched_corners=2", "merge.min_matched_corners"},
      {"--merge.max_residual_voxels=0", "merge.max_residual_voxels"},
      {"--merge.min_overlap_score=1.5", "merge.min_overlap_score"},
      {"--merge.max_seconds=-1", "merge.max_seconds"},
      {"--merge.resolution_policy=guess", "merge.resolution_policy"},
      {"--merge.fusion_rule=max", "merge.fusion_rule"},
  };
  for (const auto& [flag, name] : bad) {
    ServerConfig d;
    const Status s = Parse({flag}, &d);
    EXPECT_EQ(s.code(), StatusCode::kInvalidArgument) << flag;
    EXPECT_THAT(s.message(), HasSubstr(name)) << flag;
  }
}

TEST(ConfigTest, LongRunningSettingsParseAndAreValidated) {
  ServerConfig c;
  ASSERT_TRUE(Parse({"--fusion.mode=exact", "--fusion.cover_m=0.05", "--snapshot.every_observations=0",
                     "--snapshot.max_age_s=5", "--storage.raw_retention_days=30"},
                    &c)
                  .ok());
  EXPECT_EQ(c.fusion.mode, fusion::FusionMode::kExact);
  EXPECT_EQ(c.fusion.cover_m, 0.05);
  EXPECT_EQ(c.snapshot_every_observations, 0u);
  EXPECT_EQ(c.snapshot_max_age_s, 5.0);
  EXPECT_EQ(c.raw_retention_days, 30.0);

  const std::vector<std::pair<std::string, std::string>> bad = {
      {"--fusion.mode=fast", "fusion.mode"},
      {"--fusion.cover_m=-0.01", "cover_m"},
      {"--fusion.cover_m=nan", "cover_m"},
      {"--snapshot.every_observations=-5", "snapshot.every_observations"},
      {"--snapshot.max_age_s=0", "snapshot.max_age_s"},
      {"--snapshot.max_age_s=inf", "snapshot.max_age_s"},
      {"--storage.raw_retention_days=-1", "storage.raw_retention_days"},
      {"--storage.raw_retention_days=nan", "storage.raw_retention_days"},
  };
  for (const auto& [flag, name] : bad) {
    ServerConfig d;
    const Status s = Parse({flag}, &d);
    EXPECT_EQ(s.code(), StatusCode::kInvalidArgument) << flag;
    EXPECT_THAT(s.message(), HasSubstr(name)) << flag << ": " << s.message();
  }
}

}  // namespace
}  // namespace mapd::service
