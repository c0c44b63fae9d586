// Several maps in one mapd (--data-dir; map_directory.h, map_router.h):
// each its own frame, fused map and database file, named per call by map_id
// or the mapd-map-id metadata; old clients land in "default".
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <thread>

#include "common/health.h"
#include "server_fixture.h"
#include "service/support/auth_fixture.h"
#include "service/support/maps_fixture.h"

namespace mapd::testing {
namespace {

using ::testing::HasSubstr;

using MapsTest = MapsFixture;

TEST_F(MapsTest, TheDefaultMapIsMadeAndListed) {
  EXPECT_TRUE(std::filesystem::exists(dir_.File("default.db")));
  const pb::ListMapsResponse maps = ListMaps();
  ASSERT_EQ(maps.maps_size(), 1);
  EXPECT_EQ(maps.maps(0).map_id(), "default");
  EXPECT_TRUE(maps.can_create());
}

TEST_F(MapsTest, MapsAreApartAndOldClientsLandInDefault) {
  pb::MapInfo info;
  ASSERT_TRUE(CreateMap("site-7", &info).ok());
  EXPECT_EQ(info.map_id(), "site-7");
  EXPECT_TRUE(std::filesystem::exists(dir_.File("site-7.db")));

  for (const pb::IngestAck& ack : StreamTo("site-7", Walk("r1", 6)))
    EXPECT_EQ(ack.result(), pb::IngestAck::STORED) << ack.message();
  EXPECT_EQ(StoredBatches("site-7"), 6u);
  EXPECT_EQ(StoredBatches("default"), 0u);
  EXPECT_FALSE(FeaturesOf("site-7").empty());
  EXPECT_TRUE(FeaturesOf("default").empty());

  // A client from before maps names none: the default map, as before.
  for (const pb::IngestAck& ack : Stream(Walk("r2", 3)))
    EXPECT_EQ(ack.result(), pb::IngestAck::STORED) << ack.message();
  EXPECT_EQ(StoredBatches(""), 3u);
  EXPECT_EQ(Stats().batches(), 3u);
  EXPECT_EQ(StoredBatches("site-7"), 6u);

  const pb::ListMapsResponse maps = ListMaps();
  ASSERT_EQ(maps.maps_size(), 2);
  EXPECT_EQ(maps.maps(0).map_id(), "default");
  EXPECT_EQ(maps.maps(1).map_id(), "site-7");
  EXPECT_EQ(maps.maps(1).batches(), 6u);

  // CreateMap is the server's: audited in the default map's log.
  grpc::ClientContext ctx;
  pb::ListAuditResponse audit;
  ASSERT_TRUE(stub_->ListAudit(&ctx, {}, &audit).ok());
  ASSERT_GE(audit.entries_size(), 1);
  EXPECT_EQ(audit.entries(0).action(), "CreateMap");
  EXPECT_EQ(audit.entries(0).target(), "map site-7");
  EXPECT_EQ(audit.entries(0).result(), "ok");
  grpc::ClientContext site_ctx;
  pb::ListAuditRequest site;
  site.set_map_id("site-7");
  ASSERT_TRUE(stub_->ListAudit(&site_ctx, site, &audit).ok());
  EXPECT_EQ(audit.entries_size(), 0);  // no change to site-7's submaps or merges
}

TEST_F(MapsTest, ABatchNamingAnotherMapIsRefusedAndTheStreamGoesOn) {
  ASSERT_TRUE(CreateMap("site-7").ok());
  std::vector<pb::ObservationBatch> batches = Walk("r1", 3);
  batches[1].set_map_id("default");  // a stream of site-7 carrying a default batch
  batches[2].set_map_id("site-7");   // naming its own map is fine
  grpc::Status end;
  std::vector<pb::IngestAck> acks = StreamTo("site-7", batches, &end);
  EXPECT_TRUE(end.ok()) << end.error_message();
  ASSERT_EQ(acks.size(), 3u);
  // A refusal is answered at once, before earlier batches commit: by seq.
  std::sort(acks.begin(), acks.end(),
            [](const pb::IngestAck& a, const pb::IngestAck& b) { return a.seq() < b.seq(); });
  EXPECT_EQ(acks[0].result(), pb::IngestAck::STORED);
  EXPECT_EQ(acks[1].result(), pb::IngestAck::REJECTED);
  EXPECT_EQ(acks[1].code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_THAT(acks[1].message(), HasSubstr("this stream writes map 'site-7'"));
  EXPECT_EQ(acks[2].result(), pb::IngestAck::STORED);
  EXPECT_EQ(StoredBatches("site-7"), 2u);
  EXPECT_EQ(StoredBatches("default"), 0u);
}

TEST_F(MapsTest, UnknownOrContradictoryMapsAreRefusedWithTheReason) {
  ASSERT_TRUE(CreateMap("site-7").ok());
  // Unknown: NOT_FOUND, for a call and for a stream.
  pb::FeatureMapRequest request;
  request.set_map_id("site-8");
  Features(request);
  EXPECT_EQ(last_status_.error_code(), grpc::StatusCode::NOT_FOUND);
  EXPECT_THAT(last_status_.error_message(), HasSubstr("map 'site-8' is not served here"));
  grpc::Status end;
  EXPECT_TRUE(StreamTo("site-8", Walk("r1", 1), &end).empty());
  EXPECT_EQ(end.error_code(), grpc::StatusCode::NOT_FOUND);
  // The field and the metadata disagree.
  grpc::ClientContext ctx;
  ctx.AddMetadata("mapd-map-id", "default");
  pb::GetStatsRequest stats;
  stats.set_map_id("site-7");
  pb::Stats out;
  const grpc::Status both = stub_->GetStats(&ctx, stats, &out);
  EXPECT_EQ(both.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_THAT(both.error_message(), HasSubstr("name different maps"));
  // Ids: taken, and not an id.
  EXPECT_EQ(CreateMap("site-7").error_code(), grpc::StatusCode::ALREADY_EXISTS);
  EXPECT_EQ(CreateMap("../etc").error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_EQ(CreateMap(".hidden").error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_EQ(CreateMap("").error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_EQ(ListMaps().maps_size(), 2);
}

TEST_F(MapsTest, AMapKeepsItsOwnSettings) {
  grpc::ClientContext ctx;
  pb::CreateMapRequest request;
  request.set_map_id("site-7");
  (*request.mutable_settings())["fusion.min_support"] = "1";  // publish what one scan saw
  pb::MapInfo info;
  ASSERT_TRUE(stub_->CreateMap(&ctx, request, &info).ok());
  EXPECT_EQ(info.settings().at("fusion.min_support"), "1");
  EXPECT_TRUE(std::filesystem::exists(dir_.File("site-7.conf")));
  // One batch in each map: site-7 publishes its walls, default (min_support 3) none.
  for (const pb::IngestAck& ack : StreamTo("site-7", Walk("r1", 1)))
    EXPECT_EQ(ack.result(), pb::IngestAck::STORED) << ack.message();
  for (const pb::IngestAck& ack : Stream(Walk("r1", 1)))
    EXPECT_EQ(ack.result(), pb::IngestAck::STORED) << ack.message();
  EXPECT_FALSE(FeaturesOf("site-7").empty());
  EXPECT_TRUE(FeaturesOf("default").empty());
  // Kept across a restart.
  Restart();
  const pb::ListMapsResponse maps = ListMaps();
  ASSERT_EQ(maps.maps_size(), 2);
  EXPECT_EQ(maps.maps(1).settings().at("fusion.min_support"), "1");
  EXPECT_TRUE(maps.maps(0).settings().empty());
  EXPECT_FALSE(FeaturesOf("site-7").empty());
}

TEST_F(MapsTest, SettingsAMapMayNotHaveAreRefusedAndNothingIsMade) {
  const std::vector<std::pair<std::string, std::string>> bad = {
      {"limits.max_streams", "5"},                      // the server's, not a map's
      {"fusion.eta_m", "-1"},                           // out of range
      {"fusion.no_such_key", "1"},                      // unknown
      {"fusion.eta_m", "0.2\nlimits.max_streams = 5"},  // a second line in the file
  };
  for (const auto& [key, value] : bad) {
    grpc::ClientContext ctx;
    pb::CreateMapRequest request;
    request.set_map_id("site-7");
    (*request.mutable_settings())[key] = value;
    pb::MapInfo info;
    const grpc::Status s = stub_->CreateMap(&ctx, request, &info);
    EXPECT_EQ(s.error_code(), grpc::StatusCode::INVALID_ARGUMENT) << key;
    EXPECT_THAT(s.error_message(), HasSubstr("settings")) << key;
  }
  EXPECT_FALSE(std::filesystem::exists(dir_.File("site-7.db")));
  EXPECT_FALSE(std::filesystem::exists(dir_.File("site-7.conf")));
  EXPECT_EQ(ListMaps().maps_size(), 1);
}

TEST_F(MapsTest, HugeAndMalformedMapIdsAreRefusedWithoutHarm) {
  const std::string huge(300, 'a');
  EXPECT_EQ(CreateMap(huge).error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_EQ(CreateMap("site\n7").error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  pb::FeatureMapRequest request;
  request.set_map_id(huge);
  Features(request);
  EXPECT_EQ(last_status_.error_code(), grpc::StatusCode::NOT_FOUND);
  EXPECT_LT(last_status_.error_message().size(), 300u);  // the id is cut in the message
  grpc::ClientContext ctx;
  ctx.AddMetadata("mapd-map-id", huge);
  pb::Stats stats;
  EXPECT_EQ(stub_->GetStats(&ctx, {}, &stats).error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_EQ(ListMaps().maps_size(), 1);
}

TEST_F(MapsTest, AMalformedSettingsFileStopsTheStartNamingItAndKeepsTheMap) {
  grpc::ClientContext ctx;
  pb::CreateMapRequest request;
  request.set_map_id("site-7");
  (*request.mutable_settings())["fusion.eta_m"] = "0.2";
  pb::MapInfo info;
  ASSERT_TRUE(stub_->CreateMap(&ctx, request, &info).ok());
  for (const pb::IngestAck& ack : StreamTo("site-7", Walk("r1", 4)))
    EXPECT_EQ(ack.result(), pb::IngestAck::STORED) << ack.message();
  server_.reset();
  for (const char* text : {"fusion.eta_m\n", "fusion.eta_m = abc\n", "limits.max_streams = 5\n"}) {
    dir_.Write("site-7.conf", text);
    auto refused = service::MapServer::Start(config_);
    ASSERT_FALSE(refused.ok()) << text;
    EXPECT_THAT(refused.status().message(), HasSubstr("site-7.conf")) << text;
  }
  // Mended, the map comes back with everything it stored.
  dir_.Write("site-7.conf", "fusion.eta_m = 0.2\n");
  StartServer();
  EXPECT_EQ(StoredBatches("site-7"), 4u);
}

TEST_F(MapsTest, AnUploadHeaderNamingAnotherMapIsRefused) {
  ASSERT_TRUE(CreateMap("site-7").ok());
  grpc::ClientContext ctx;
  ctx.AddMetadata("mapd-map-id", "site-7");
  pb::SubmapInfo info;
  auto writer = stub_->UploadSubmap(&ctx, &info);
  pb::UploadSubmapRequest header;
  header.mutable_header()->set_robot_id("r1");
  header.mutable_header()->set_name("room");
  header.mutable_header()->set_format(pb::SUBMAP_FORMAT_OCTOMAP_BT);
  header.mutable_header()->set_map_id("default");
  writer->Write(header);
  writer->WritesDone();
  const grpc::Status s = writer->Finish();
  EXPECT_EQ(s.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_THAT(s.error_message(), HasSubstr("this upload stream is for map 'site-7'"));
}

TEST_F(MapsTest, MapsComeBackAfterARestartAndEachHasItsHealth) {
  ASSERT_TRUE(CreateMap("site-7").ok());
  for (const pb::IngestAck& ack : StreamTo("site-7", Walk("r1", 6)))
    EXPECT_EQ(ack.result(), pb::IngestAck::STORED) << ack.message();
  const size_t features = FeaturesOf("site-7").size();
  ASSERT_GT(features, 0u);
  Restart();
  EXPECT_EQ(ListMaps().maps_size(), 2);
  EXPECT_EQ(FeaturesOf("site-7").size(), features);
  EXPECT_TRUE(FeaturesOf("default").empty());

  Health health = Health::kUnknown;
  for (int i = 0; i < 200 && health != Health::kServing; ++i) {
    health = CheckHealth(channel_, std::chrono::seconds(5), "map/site-7");
    if (health != Health::kServing) std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  EXPECT_EQ(health, Health::kServing);
  EXPECT_EQ(CheckHealth(channel_, std::chrono::seconds(5), "map/default"), Health::kServing);
  EXPECT_EQ(CheckHealth(channel_, std::chrono::seconds(5), "map/site-8"), Health::kError);
}

TEST_F(MapsTest, ASecondMapdOnTheSameDirectoryRefusesToStart) {
  service::ServerConfig second = config_;
  auto other = service::MapServer::Start(second);
  ASSERT_FALSE(other.ok());
  EXPECT_EQ(other.status().code(), StatusCode::kFailedPrecondition);
  EXPECT_THAT(other.status().message(), HasSubstr("in use by another mapd"));
  // The first goes on.
  for (const pb::IngestAck& ack : Stream(Walk("r1", 2)))
    EXPECT_EQ(ack.result(), pb::IngestAck::STORED) << ack.message();
}

TEST_F(MapsTest, AFileThatIsNotAMapIdStopsTheStartWithItsName) {
  server_.reset();
  dir_.Write(".backup.db", "");
  auto server = service::MapServer::Start(config_);
  ASSERT_FALSE(server.ok());
  EXPECT_THAT(server.status().message(), HasSubstr(".backup.db"));
}

// Tokens scoped to maps (docs/security.md): a site's robot writes its site only.
class ScopedTokenTest : public AuthFixture {
 protected:
  void SetUp() override {
    Configure();
    UseDataDir();
    StartServer();
    MakeTokens();
    for (const char* id : {"site-7", "site-8"}) {
      pb::CreateMapRequest request;
      request.set_map_id(id);
      pb::MapInfo info;
      auto ctx = As(admin_);
      const grpc::Status s = stub_->CreateMap(ctx.get(), request, &info);
      ASSERT_TRUE(s.ok()) << s.error_message();
    }
  }
  std::vector<pb::IngestAck> StreamTo(const std::string& token, const std::string& map,
                                      const std::vector<pb::ObservationBatch>& batches,
                                      grpc::Status* status) {
    auto ctx = As(token);
    ctx->AddMetadata("mapd-map-id", map);
    auto stream = stub_->Ingest(ctx.get());
    for (const auto& b : batches) stream->Write(b);
    stream->WritesDone();
    std::vector<pb::IngestAck> acks;
    pb::IngestAck ack;
    while (stream->Read(&ack)) acks.push_back(ack);
    *status = stream->Finish();
    return acks;
  }
};

TEST_F(ScopedTokenTest, ARobotOfOneSiteCannotTouchAnother) {
  std::string site7;
  ASSERT_TRUE(CreateTokenAs(admin_, pb::ROLE_ROBOT, "r1-site-7", "r1", &site7, {"site-7"}).ok());
  grpc::Status end;
  const auto stored = StreamTo(site7, "site-7", Walk("r1", 3), &end);
  EXPECT_TRUE(end.ok()) << end.error_message();
  ASSERT_EQ(stored.size(), 3u);
  for (const pb::IngestAck& ack : stored) EXPECT_EQ(ack.result(), pb::IngestAck::STORED);
  for (const char* other : {"site-8", "default"}) {
    EXPECT_TRUE(StreamTo(site7, other, Walk("r1", 2), &end).empty());
    EXPECT_EQ(end.error_code(), grpc::StatusCode::PERMISSION_DENIED) << other;
    EXPECT_THAT(end.error_message(), HasSubstr("may act on maps site-7 only"));
  }
  // Reads too: its map only, and ListMaps names only that one.
  EXPECT_EQ(StatsAs(site7).error_code(), grpc::StatusCode::PERMISSION_DENIED);  // default
  auto ctx = As(site7);
  pb::ListMapsResponse maps;
  ASSERT_TRUE(stub_->ListMaps(ctx.get(), {}, &maps).ok());
  ASSERT_EQ(maps.maps_size(), 1);
  EXPECT_EQ(maps.maps(0).map_id(), "site-7");
  // The refusal is in the audit log, naming the map.
  bool audited = false;
  for (const pb::AuditEntry& e : Audit(admin_))
    audited = audited || (e.who() == "r1-site-7" && e.target() == "map site-8");
  EXPECT_TRUE(audited);
  // The admin's list shows the scope.
  auto list = As(admin_);
  pb::ListTokensResponse tokens;
  ASSERT_TRUE(stub_->ListTokens(list.get(), {}, &tokens).ok());
  bool listed = false;
  for (const pb::TokenInfo& t : tokens.tokens())
    listed = listed || (t.name() == "r1-site-7" && t.maps_size() == 1 && t.maps(0) == "site-7");
  EXPECT_TRUE(listed);
}

TEST_F(ScopedTokenTest, AScopedAdminManagesNeitherTokensNorMaps) {
  std::string scoped;
  ASSERT_TRUE(CreateTokenAs(admin_, pb::ROLE_ADMIN, "site-7-admin", "", &scoped, {"site-7"}).ok());
  const grpc::Status create = CreateTokenAs(scoped, pb::ROLE_ADMIN, "escalated");
  EXPECT_EQ(create.error_code(), grpc::StatusCode::PERMISSION_DENIED);
  EXPECT_THAT(create.error_message(), HasSubstr("scoped to maps"));
  pb::CreateMapRequest request;
  request.set_map_id("site-9");
  pb::MapInfo info;
  auto ctx = As(scoped);
  EXPECT_EQ(stub_->CreateMap(ctx.get(), request, &info).error_code(),
            grpc::StatusCode::PERMISSION_DENIED);
  for (const char* map : {"site-7", "default"}) {
    pb::DeleteMapRequest remove;
    remove.set_map_id(map);
    pb::DeleteMapResponse removed;
    auto delete_ctx = As(scoped);
    EXPECT_EQ(stub_->DeleteMap(delete_ctx.get(), remove, &removed).error_code(),
              grpc::StatusCode::PERMISSION_DENIED)
        << map;
    pb::RestoreMapRequest restore;
    restore.set_map_id(map);
    auto restore_ctx = As(scoped);
    EXPECT_EQ(stub_->RestoreMap(restore_ctx.get(), restore, &info).error_code(),
              grpc::StatusCode::PERMISSION_DENIED)
        << map;
  }
  // A map id that is not one is refused when the token is made.
  const grpc::Status bad = CreateTokenAs(admin_, pb::ROLE_READER, "bad", "", nullptr, {"../x"});
  EXPECT_EQ(bad.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_THAT(bad.error_message(), HasSubstr("not a map id"));
}

// One database (--db): the default map only; CreateMap says how to get more.
TEST_F(ServerFixture, ASingleDatabaseServesTheDefaultMapOnly) {
  grpc::ClientContext list_ctx;
  pb::ListMapsResponse maps;
  ASSERT_TRUE(stub_->ListMaps(&list_ctx, {}, &maps).ok());
  ASSERT_EQ(maps.maps_size(), 1);
  EXPECT_EQ(maps.maps(0).map_id(), "default");
  EXPECT_FALSE(maps.can_create());
  grpc::ClientContext ctx;
  pb::CreateMapRequest request;
  request.set_map_id("site-7");
  pb::MapInfo info;
  const grpc::Status s = stub_->CreateMap(&ctx, request, &info);
  EXPECT_EQ(s.error_code(), grpc::StatusCode::FAILED_PRECONDITION);
  EXPECT_THAT(s.error_message(), HasSubstr("--data-dir"));
  // A second server on the same file refuses to start.
  auto other = service::MapServer::Start(config_);
  ASSERT_FALSE(other.ok());
  EXPECT_THAT(other.status().message(), HasSubstr("in use by another mapd"));
}

}  // namespace
}  // namespace mapd::testing
