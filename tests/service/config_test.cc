// mapd's configuration: defaults (the libraries' own), the config file and
// flags, ranges and rules, and the generated help and example file.
#include "service/config.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <string>
#include <utility>
#include <vector>

#include "common/temp_dir.h"
#include "mapd/command_line.h"
#include "service/map_core.h"
#include "storage/store.h"

namespace mapd::service {
namespace {

using ::mapd::AddFlags;
using ::mapd::ApplyCommandLine;
using ::mapd::CommandLine;
using ::testing::HasSubstr;

// Settings as mapd gets them: parsed by its command line (CLI11), then the
// config files and flags applied and validated.
Status Parse(std::vector<std::string> args, ServerConfig* c, CommandLine* line = nullptr,
             std::string* help = nullptr) {
  CLI::App app("mapd", "mapd");
  CommandLine parsed;
  AddFlags(&app, &parsed);
  if (help != nullptr) *help = app.help();
  std::reverse(args.begin(), args.end());  // CLI11 takes a vector from its back
  try {
    app.parse(args);
  } catch (const CLI::ParseError& e) {
    return Status::InvalidArgument(e.what());
  }
  if (line != nullptr) *line = parsed;
  return ApplyCommandLine(parsed, c);
}

TEST(ConfigTest, DefaultsAreValidAndLoopback) {
  ServerConfig c;
  EXPECT_TRUE(c.Validate().ok());
  EXPECT_EQ(c.listen, "127.0.0.1:50051");
}

// mapd's defaults are the libraries' own: the option structs it fills
// (MapCore's, the store's, the fusion parameters) default to the same values,
// so a default changed on one side and not the other fails here. (The merge
// thresholds against voxel::MergeParams: submap_service_test.cc, built with
// the voxel library.)
TEST(ConfigTest, DefaultsAreThoseOfTheOptionStructsTheyFill) {
  const ServerConfig c;
  EXPECT_EQ(fusion::FusionParamsKey(c.fusion), fusion::FusionParamsKey(fusion::FusionParams{}));
  EXPECT_EQ(fusion::PlaneFusionParamsKey(c.planes),
            fusion::PlaneFusionParamsKey(fusion::PlaneFusionParams{}));
  const MapCoreOptions core;
  EXPECT_EQ(fusion::FusionParamsKey(c.fusion), fusion::FusionParamsKey(core.fusion));
  EXPECT_EQ(c.max_group_batches, core.max_group_batches);
  EXPECT_EQ(c.snapshot_every_observations, core.snapshot_every_observations);
  EXPECT_EQ(c.snapshot_max_age_s, core.snapshot_max_age_s);
  EXPECT_EQ(c.raw_retention_days, core.raw_retention_days);
  EXPECT_EQ(c.shutdown_flush_s, core.stop_flush_s);
  EXPECT_EQ(c.watch.history, core.watch.history);
  EXPECT_EQ(c.watch.queue, core.watch.queue);
  EXPECT_EQ(c.watch.max_watchers, core.watch.max_watchers);
  const storage::StoreOptions store;
  EXPECT_EQ(c.sync_full, store.synchronous_full);
  EXPECT_EQ(c.busy_timeout_ms, store.busy_timeout_ms);
  EXPECT_EQ(c.max_db_bytes, store.max_db_bytes);
  EXPECT_EQ(c.busy_timeout_ms, core.store.busy_timeout_ms);
}

TEST(ConfigTest, FlagsOverrideTheConfigFileWhateverTheirOrder) {
  mapd::testing::TempDir dir;
  std::ofstream(dir.File("mapd.conf"))
      << "# comment\nfusion.gamma = 0.5\nfusion.eta_m=0.2\nsync = full\n";
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
  EXPECT_THAT(Parse({"--no-such-thing=1"}, &e).message(), HasSubstr("--no-such-thing"));
  ServerConfig f;
  EXPECT_THAT(Parse({"--db"}, &f).message(), HasSubstr("--db"));
  EXPECT_EQ(ApplySetting("no-such-thing", "1", &f).message(),
            "unknown setting 'no-such-thing' (see mapd --help)");
}

// gRPC took the port modulo 65536: --listen 127.0.0.1:99999 served on 34463.
TEST(ConfigTest, AListenPortOutsideItsRangeIsRefused) {
  for (const char* listen : {"127.0.0.1:99999", "127.0.0.1:65536", "127.0.0.1:", "127.0.0.1:x1",
                             "127.0.0.1:-1", "127.0.0.1:0123456"}) {
    ServerConfig c;
    Status s = Parse({"--listen", listen}, &c);
    if (s.ok()) s = c.Validate();
    EXPECT_THAT(s.message(), HasSubstr("0..65535")) << listen;
  }
  for (const char* listen : {"127.0.0.1:0", "127.0.0.1:65535", "[::1]:50051"}) {
    ServerConfig c;
    ASSERT_TRUE(Parse({"--listen", listen}, &c).ok()) << listen;
    EXPECT_TRUE(c.Validate().ok()) << listen << ": " << c.Validate().ToString();
  }
}

// The health port is plaintext: loopback only, and a port in range.
TEST(ConfigTest, TheHealthPortIsALoopbackHostPort) {
  for (const auto& [value, why] : std::vector<std::pair<const char*, const char*>>{
           {"0.0.0.0:50052", "not a loopback host:port"},
           {"10.1.2.3:50052", "not a loopback host:port"},
           {"127.0.0.1:70000", "0..65535"},
           {"127.0.0.1", "is not host:port"}}) {
    ServerConfig c;
    Status s = Parse({"--health_listen", value}, &c);
    if (s.ok()) s = c.Validate();
    EXPECT_THAT(s.message(), HasSubstr("health_listen: '" + std::string(value))) << value;
    EXPECT_THAT(s.message(), HasSubstr(why)) << value;
  }
  ServerConfig c;
  ASSERT_TRUE(Parse({"--health_listen", "127.0.0.1:50052"}, &c).ok());
  EXPECT_TRUE(c.Validate().ok());
}

// Found while writing tests/fuzz/config_fuzz.cc: the parser before the
// settings table wrapped integers into their field (4294967300 became 4 for
// merge.min_matched_corners) and took " -1" as 2^32 - 1.
TEST(ConfigTest, IntegersThatDoNotFitOrAreNotPlainDigitsAreRefused) {
  for (const auto& [key, value] : std::vector<std::pair<std::string, std::string>>{
           {"merge.min_matched_corners", "4294967300"},          // int
           {"limits.max_features_per_batch", "4294967297"},      // uint32
           {"limits.max_in_flight", "99999999999999999999999"},  // beyond 64 bits
           {"busy_timeout_ms", "2147483648"},
           {"limits.max_in_flight", " -1"},
           {"fusion.min_support", "+3"},
           {"limits.max_group_batches", "12abc"}}) {
    ServerConfig c;
    const ServerConfig before;
    const Status s = ApplySetting(key, value, &c);
    EXPECT_FALSE(s.ok()) << key << " = '" << value << "'";
    EXPECT_THAT(s.message(), HasSubstr(key));
    EXPECT_EQ(c.ingest.max_in_flight, before.ingest.max_in_flight);
    EXPECT_EQ(c.submaps.min_matched_corners, before.submaps.min_matched_corners);
  }
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
  EXPECT_TRUE(Parse({"--listen", "0.0.0.0:50051", "--allow_insecure_remote", "true",
                     "--auth.required", "true"},
                    &d)
                  .ok());
}

TEST(ConfigTest, RemoteListenNeedsAuth) {
  ServerConfig c;
  const Status s =
      Parse({"--listen", "0.0.0.0:50051", "--tls_cert", "c.pem", "--tls_key", "k.pem"}, &c);
  EXPECT_THAT(s.message(), HasSubstr("auth.required"));
  ServerConfig d;
  EXPECT_TRUE(Parse({"--listen", "0.0.0.0:50051", "--tls_cert", "c.pem", "--tls_key", "k.pem",
                     "--tls_client_ca", "ca.pem"},
                    &d)
                  .ok());
  ServerConfig e;
  EXPECT_THAT(Parse({"--tls_client_ca", "ca.pem"}, &e).message(),
              HasSubstr("tls_client_ca needs tls_cert"));
  ServerConfig f;
  EXPECT_THAT(Parse({"--auth.required", "maybe"}, &f).message(), HasSubstr("auth.required"));
}

TEST(ConfigTest, SubmapAndMergeSettingsParseAndAreValidated) {
  ServerConfig c;
  ASSERT_TRUE(
      Parse({"--limits.max_submap_bytes", "1048576", "--limits.max_concurrent_merges=2",
             "--limits.max_queued_merges=0", "--merge.min_matched_corners=6",
             "--merge.max_residual_voxels=1.5", "--merge.min_overlap_score=0.5",
             "--merge.min_shared_free_ratio=0", "--merge.max_restart_spread_voxels=0",
             "--merge.max_seconds=10", "--merge.resolution_policy=resample",
             "--merge.fusion_rule=log_odds", "--merge.correlation=false",
             "--merge.correlation_check_accepted=no", "--merge.correlation_after_corner_stages=0",
             "--merge.correlation_max_cells=4000000", "--merge.correlation_looser_stages=yes",
             "--merge.correlation_plan_view_first_cells=0"},
            &c)
          .ok());
  EXPECT_EQ(c.submaps.max_submap_bytes, 1048576u);
  EXPECT_EQ(c.submaps.max_concurrent_merges, 2u);
  EXPECT_EQ(c.submaps.max_queued_merges, 0u);
  EXPECT_EQ(c.submaps.min_matched_corners, 6);
  EXPECT_EQ(c.submaps.max_residual_voxels, 1.5);
  EXPECT_EQ(c.submaps.min_overlap_score, 0.5);
  EXPECT_EQ(c.submaps.min_shared_free_ratio, 0.0);
  EXPECT_EQ(c.submaps.max_restart_spread_voxels, 0.0);
  EXPECT_EQ(c.submaps.max_merge_seconds, 10.0);
  EXPECT_TRUE(c.submaps.resample_resolutions);
  EXPECT_TRUE(c.submaps.log_odds_fusion);
  EXPECT_FALSE(c.submaps.correlation);
  EXPECT_FALSE(c.submaps.correlation_check_accepted);
  EXPECT_EQ(c.submaps.correlation_after_corner_stages, 0);
  EXPECT_EQ(c.submaps.correlation_max_cells, 4'000'000u);
  EXPECT_TRUE(c.submaps.correlation_looser_stages_after_refusal);
  EXPECT_EQ(c.submaps.correlation_plan_view_first_cells, 0u);
  // Every value above differs from its default, so each flag was applied.
  // (The defaults are voxel::CorrelationParams's: submap_service_test.cc.)
  const SubmapOptions defaults;
  EXPECT_NE(c.submaps.correlation, defaults.correlation);
  EXPECT_NE(c.submaps.correlation_check_accepted, defaults.correlation_check_accepted);
  EXPECT_NE(c.submaps.correlation_max_cells, defaults.correlation_max_cells);
  EXPECT_NE(c.submaps.correlation_plan_view_first_cells,
            defaults.correlation_plan_view_first_cells);
  EXPECT_NE(c.submaps.correlation_looser_stages_after_refusal,
            defaults.correlation_looser_stages_after_refusal);
  EXPECT_NE(c.submaps.min_matched_corners, defaults.min_matched_corners);
  EXPECT_NE(c.submaps.max_residual_voxels, defaults.max_residual_voxels);
  EXPECT_NE(c.submaps.min_overlap_score, defaults.min_overlap_score);

  const std::vector<std::pair<std::string, std::string>> bad = {
      {"--limits.max_concurrent_merges=0", "limits.max_concurrent_merges"},
      {"--limits.max_submap_bytes=10", "limits.max_submap_bytes"},
      {"--merge.min_matched_corners=2", "merge.min_matched_corners"},
      {"--merge.max_residual_voxels=0", "merge.max_residual_voxels"},
      {"--merge.min_overlap_score=1.5", "merge.min_overlap_score"},
      {"--merge.min_shared_free_ratio=-1", "merge.min_shared_free_ratio"},
      {"--merge.max_restart_spread_voxels=-1", "merge.max_restart_spread_voxels"},
      {"--merge.max_seconds=-1", "merge.max_seconds"},
      {"--merge.resolution_policy=guess", "merge.resolution_policy"},
      {"--merge.fusion_rule=max", "merge.fusion_rule"},
      {"--merge.correlation_after_corner_stages=101", "merge.correlation_after_corner_stages"},
      {"--merge.correlation=maybe", "merge.correlation"},
      {"--merge.correlation_max_cells=999", "merge.correlation_max_cells"},
      {"--merge.correlation_plan_view_first_cells=300000000",
       "merge.correlation_plan_view_first_cells"},
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
  ASSERT_TRUE(
      Parse({"--fusion.mode=exact", "--fusion.cover_m=0.05", "--snapshot.every_observations=0",
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

// Issue 46's limits on what one observation can cost.
TEST(ConfigTest, CostLimitsParseAndAreValidated) {
  ServerConfig c;
  ASSERT_TRUE(Parse({"--fusion.max_component_nodes=512", "--fusion.max_link_candidates=100",
                     "--fusion.evidence_range_m=40", "--fusion.max_wall_length_m=2000",
                     "--limits.max_feature_length_m=1500", "--limits.fusion_share_after_s=0",
                     "--limits.fusion_share_factor=3", "--fusion.max_wall_pieces=64"},
                    &c)
                  .ok());
  EXPECT_EQ(c.fusion.max_component_nodes, 512u);
  EXPECT_EQ(c.fusion.max_link_candidates, 100u);
  EXPECT_EQ(c.fusion.evidence_range_m, 40.0);
  EXPECT_EQ(c.ingest.limits.max_feature_length_m, 1500.0);
  EXPECT_EQ(c.fusion_share_after_s, 0.0);
  EXPECT_EQ(c.fusion_share_factor, 3.0);
  EXPECT_EQ(c.fusion.max_wall_pieces, 64u);
  const std::vector<std::pair<std::string, std::string>> bad = {
      {"--fusion.max_component_nodes=8", "fusion.max_component_nodes"},
      {"--fusion.max_wall_pieces=nan", "fusion.max_wall_pieces"},
      {"--fusion.max_wall_pieces=2000000", "fusion.max_wall_pieces"},
      {"--fusion.evidence_range_m=0", "fusion.evidence_range_m"},
      {"--limits.fusion_share_factor=0.5", "limits.fusion_share_factor"},
      // A batch the fuser would refuse must not be acknowledged.
      {"--limits.max_feature_length_m=5000", "at most fusion.max_wall_length_m"},
  };
  for (const auto& [flag, name] : bad) {
    ServerConfig d;
    Status s = Parse({flag}, &d);
    if (s.ok()) s = d.Validate();
    EXPECT_EQ(s.code(), StatusCode::kInvalidArgument) << flag;
    EXPECT_THAT(s.message(), HasSubstr(name)) << flag << ": " << s.message();
  }
}

// One source of truth: the example file is what --print-config writes for the
// defaults (regenerate it with `mapd --print-config > deploy/mapd.conf.example`),
// and reading it back changes nothing.
TEST(ConfigTest, TheExampleFileIsTheDefaults) {
  EXPECT_EQ(mapd::testing::ReadFileBytes(MAPD_EXAMPLE_CONFIG), ConfigFileText(ServerConfig()));
  ServerConfig loaded;
  ASSERT_TRUE(LoadConfigFile(MAPD_EXAMPLE_CONFIG, &loaded).ok());
  EXPECT_EQ(ConfigFileText(loaded), ConfigFileText(ServerConfig()));
}

TEST(ConfigTest, HelpShowsTheRealDefaults) {
  ServerConfig c;
  std::string help;
  ASSERT_TRUE(Parse({}, &c, nullptr, &help).ok());
  // `--key <number>=value` then a space or a line end, value as the code has
  // it (the settings table prints 15 significant digits).
  auto shows = [&](const std::string& key, double value) {
    char text[32];
    std::snprintf(text, sizeof text, "%.15g", value);
    std::string pattern = "--" + key + " <number>=" + text;
    for (size_t i = 0; (i = pattern.find('.', i)) != std::string::npos; i += 2)
      pattern.insert(i, "\\");
    EXPECT_THAT(help, ::testing::ContainsRegex(pattern + "[[:space:]]")) << key << " = " << text;
  };
  // These two once showed 2 and 0.3 while the code used 0.75 and 0.9.
  const SubmapOptions submaps;
  shows("merge.max_residual_voxels", submaps.max_residual_voxels);
  shows("merge.min_overlap_score", submaps.min_overlap_score);
  shows("fusion.delta_deg", fusion::FusionParams().delta_rad * 180.0 / M_PI);
  shows("fusion.gamma", fusion::FusionParams().gamma);
  EXPECT_THAT(help, HasSubstr("--sync <normal|full>=normal "));
}

TEST(ConfigTest, PrintedConfigReadsBackToTheSameSettings) {
  ServerConfig c;
  ASSERT_TRUE(Parse({"--fusion.delta_deg=7.5", "--sync=full", "--merge.fusion_rule=log_odds",
                     "--limits.max_in_flight=9", "--fusion.mode=exact"},
                    &c)
                  .ok());
  mapd::testing::TempDir dir;
  std::ofstream(dir.File("printed.conf")) << ConfigFileText(c);
  ServerConfig back;
  ASSERT_TRUE(LoadConfigFile(dir.File("printed.conf"), &back).ok());
  EXPECT_EQ(ConfigFileText(back), ConfigFileText(c));
  EXPECT_NEAR(back.fusion.delta_rad, c.fusion.delta_rad, 1e-15);
}

TEST(ConfigTest, RangesAreCheckedForParsedAndBuiltConfigs) {
  ServerConfig c;
  EXPECT_THAT(Parse({"--limits.max_in_flight=0"}, &c).message(),
              HasSubstr("limits.max_in_flight = 0 is outside [1, 1000000]"));
  ServerConfig d;
  EXPECT_THAT(Parse({"--busy_timeout_ms=-1"}, &d).message(), HasSubstr("busy_timeout_ms"));
  ServerConfig e;
  EXPECT_THAT(Parse({"--limits.max_message_bytes=99999999999999999999999"}, &e).message(),
              HasSubstr("limits.max_message_bytes"));
  ServerConfig built;
  built.busy_timeout_ms = -5;
  EXPECT_THAT(built.Validate().message(), HasSubstr("busy_timeout_ms = -5 is negative"));
  ServerConfig nan;
  nan.submaps.min_overlap_score = std::nan("");
  EXPECT_THAT(nan.Validate().message(), HasSubstr("merge.min_overlap_score"));
}

TEST(ConfigTest, VersionAndPrintConfigAreActions) {
  ServerConfig c;
  CommandLine line;
  ASSERT_TRUE(Parse({"--version"}, &c, &line).ok());
  EXPECT_TRUE(line.version);
  ASSERT_TRUE(Parse({"--fusion.gamma=0.4", "--print-config"}, &c, &line).ok());
  EXPECT_TRUE(line.print_config);
  EXPECT_FALSE(line.version);
  EXPECT_THAT(ConfigFileText(c), HasSubstr("fusion.gamma = 0.4\n"));
}

// The addresses a listen host stands for decide, not its text.
TEST(ConfigTest, LoopbackIsDecidedByTheResolvedAddresses) {
  EXPECT_TRUE(ListenIsLoopback("127.0.0.1:50051"));
  EXPECT_TRUE(ListenIsLoopback("[::1]:50051"));
  EXPECT_TRUE(ListenIsLoopback("localhost:50051"));
  EXPECT_TRUE(ListenIsLoopback("unix:/tmp/mapd.sock"));
  EXPECT_FALSE(ListenIsLoopback("0.0.0.0:50051"));
  EXPECT_FALSE(ListenIsLoopback("0:50051"));  // resolves to 0.0.0.0
  EXPECT_FALSE(ListenIsLoopback("[::]:50051"));
  EXPECT_FALSE(ListenIsLoopback(":50051"));
  // Starts like a loopback address but is a (here unresolvable) host name.
  EXPECT_FALSE(ListenIsLoopback("127.0.0.1.example.invalid:50051"));
  ServerConfig c;
  EXPECT_THAT(Parse({"--listen", "0:50051"}, &c).message(), HasSubstr("tls_cert"));
}

}  // namespace
}  // namespace mapd::service
