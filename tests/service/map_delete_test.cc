// Deleting and restoring maps (DeleteMap, RestoreMap; map_lifecycle.h) on a
// --data-dir: an archived map leaves service with its files moved to
// DIR/archive/, comes back as it was, and a purged one is gone for good.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <filesystem>

#include "server_fixture.h"
#include "service/support/maps_fixture.h"

namespace mapd::testing {
namespace {

using ::testing::HasSubstr;

class MapDeleteTest : public MapsFixture {
 protected:
  grpc::Status DeleteMap(const std::string& id, bool purge, pb::DeleteMapResponse* out = nullptr) {
    grpc::ClientContext ctx;
    pb::DeleteMapRequest request;
    request.set_map_id(id);
    request.set_purge(purge);
    pb::DeleteMapResponse ignored;
    return stub_->DeleteMap(&ctx, request, out != nullptr ? out : &ignored);
  }
  grpc::Status RestoreMap(const std::string& id, pb::MapInfo* out = nullptr) {
    grpc::ClientContext ctx;
    pb::RestoreMapRequest request;
    request.set_map_id(id);
    pb::MapInfo ignored;
    return stub_->RestoreMap(&ctx, request, out != nullptr ? out : &ignored);
  }
  std::vector<std::string> ArchivedIds() {
    grpc::ClientContext ctx;
    pb::ListMapsRequest request;
    request.set_archived(true);
    pb::ListMapsResponse maps;
    EXPECT_TRUE(stub_->ListMaps(&ctx, request, &maps).ok());
    std::vector<std::string> ids;
    for (const pb::MapInfo& m : maps.maps()) {
      EXPECT_GT(m.archived_ns(), 0) << m.map_id();
      ids.push_back(m.map_id());
    }
    return ids;
  }
  grpc::StatusCode StatsCode(const std::string& map) {
    grpc::ClientContext ctx;
    pb::GetStatsRequest request;
    request.set_map_id(map);
    pb::Stats stats;
    return stub_->GetStats(&ctx, request, &stats).error_code();
  }
  // A map with a robot's walk in it; its fused map.
  std::string MakeMap(const std::string& id) {
    EXPECT_TRUE(CreateMap(id).ok());
    for (const pb::IngestAck& ack : StreamTo(id, Walk("r1", 6)))
      EXPECT_EQ(ack.result(), pb::IngestAck::STORED) << ack.message();
    const std::string fused = FusedOf(id);
    EXPECT_FALSE(fused.empty());
    return fused;
  }
  std::string FusedOf(const std::string& id) {
    std::string fused;
    for (const pb::FusedFeature& f : FeaturesOf(id)) fused += f.SerializeAsString();
    return fused;
  }
};

TEST_F(MapDeleteTest, ADeletedMapIsArchivedUnservedAndRestoredAsItWas) {
  MakeMap("site-7");
  // A robot streaming while the map is deleted: its batch is acknowledged,
  // then its stream ends UNAVAILABLE.
  grpc::ClientContext stream_ctx;
  stream_ctx.AddMetadata("mapd-map-id", "site-7");
  auto stream = stub_->Ingest(&stream_ctx);
  ASSERT_TRUE(stream->Write(Walk("r2", 1)[0]));
  pb::IngestAck ack;
  ASSERT_TRUE(stream->Read(&ack));
  EXPECT_EQ(ack.result(), pb::IngestAck::STORED);
  const std::string fused = FusedOf("site-7");  // r2's batch in it

  pb::DeleteMapResponse deleted;
  const grpc::Status s = DeleteMap("site-7", false, &deleted);
  ASSERT_TRUE(s.ok()) << s.error_message();
  EXPECT_FALSE(deleted.purged());
  EXPECT_THAT(deleted.where(), HasSubstr("archive/site-7.db"));
  while (stream->Read(&ack)) {
  }
  EXPECT_EQ(stream->Finish().error_code(), grpc::StatusCode::UNAVAILABLE);

  EXPECT_FALSE(std::filesystem::exists(dir_.File("site-7.db")));
  EXPECT_TRUE(std::filesystem::exists(dir_.File("archive/site-7.db")));
  EXPECT_EQ(StatsCode("site-7"), grpc::StatusCode::NOT_FOUND);
  ASSERT_EQ(ListMaps().maps_size(), 1);
  EXPECT_THAT(ArchivedIds(), ::testing::ElementsAre("site-7"));
  // Its id stays taken, and archiving twice says what to do instead.
  grpc::Status again = CreateMap("site-7");
  EXPECT_EQ(again.error_code(), grpc::StatusCode::ALREADY_EXISTS);
  EXPECT_THAT(again.error_message(), HasSubstr("is archived"));
  again = DeleteMap("site-7", false);
  EXPECT_EQ(again.error_code(), grpc::StatusCode::FAILED_PRECONDITION);
  EXPECT_THAT(again.error_message(), HasSubstr("--purge"));

  // Restored in the same process: the map's file lock went with it.
  pb::MapInfo info;
  const grpc::Status restored = RestoreMap("site-7", &info);
  ASSERT_TRUE(restored.ok()) << restored.error_message();
  EXPECT_TRUE(info.serving());
  EXPECT_EQ(FusedOf("site-7"), fused);
  EXPECT_EQ(StoredBatches("site-7"), 7u);
  EXPECT_TRUE(ArchivedIds().empty());
  for (const pb::IngestAck& a : StreamTo("site-7", Walk("r3", 2)))
    EXPECT_EQ(a.result(), pb::IngestAck::STORED) << a.message();

  // Both are the server's actions, in the default map's log.
  grpc::ClientContext ctx;
  pb::ListAuditResponse audit;
  ASSERT_TRUE(stub_->ListAudit(&ctx, {}, &audit).ok());
  ASSERT_GE(audit.entries_size(), 2);
  EXPECT_EQ(audit.entries(0).action(), "RestoreMap");
  EXPECT_EQ(audit.entries(0).result(), "ok");
  bool deleted_audited = false;
  for (const pb::AuditEntry& e : audit.entries())
    deleted_audited = deleted_audited || (e.action() == "DeleteMap" && e.target() == "map site-7");
  EXPECT_TRUE(deleted_audited);
}

TEST_F(MapDeleteTest, AnArchiveOutlivesARestart) {
  const std::string fused = MakeMap("site-7");
  ASSERT_TRUE(DeleteMap("site-7", false).ok());
  Restart();
  ASSERT_EQ(ListMaps().maps_size(), 1);  // a start serves DIR's own files only
  EXPECT_THAT(ArchivedIds(), ::testing::ElementsAre("site-7"));
  ASSERT_TRUE(RestoreMap("site-7").ok());
  EXPECT_EQ(FusedOf("site-7"), fused);
  Restart();
  EXPECT_EQ(ListMaps().maps_size(), 2);
}

TEST_F(MapDeleteTest, APurgedMapIsGoneForGoodAndItsIdIsFreeAgain) {
  MakeMap("site-7");
  pb::DeleteMapResponse deleted;
  ASSERT_TRUE(DeleteMap("site-7", true, &deleted).ok());
  EXPECT_TRUE(deleted.purged());
  EXPECT_TRUE(deleted.where().empty());
  EXPECT_FALSE(std::filesystem::exists(dir_.File("site-7.db")));
  EXPECT_FALSE(std::filesystem::exists(dir_.File("archive/site-7.db")));
  EXPECT_TRUE(ArchivedIds().empty());
  EXPECT_EQ(RestoreMap("site-7").error_code(), grpc::StatusCode::NOT_FOUND);
  ASSERT_TRUE(CreateMap("site-7").ok());
  EXPECT_EQ(StoredBatches("site-7"), 0u);
  EXPECT_TRUE(FeaturesOf("site-7").empty());

  // An archived map is purged too.
  MakeMap("site-8");
  ASSERT_TRUE(DeleteMap("site-8", false).ok());
  ASSERT_TRUE(DeleteMap("site-8", true).ok());
  EXPECT_FALSE(std::filesystem::exists(dir_.File("archive/site-8.db")));
  EXPECT_EQ(DeleteMap("site-8", true).error_code(), grpc::StatusCode::NOT_FOUND);
}

TEST_F(MapDeleteTest, WhatCannotBeDeletedIsRefusedWithTheReasonAndNothingChanges) {
  MakeMap("site-7");
  grpc::Status s = DeleteMap("default", true);
  EXPECT_EQ(s.error_code(), grpc::StatusCode::FAILED_PRECONDITION);
  EXPECT_THAT(s.error_message(), HasSubstr("default map cannot be deleted"));
  s = DeleteMap("site-9", false);
  EXPECT_EQ(s.error_code(), grpc::StatusCode::NOT_FOUND);
  EXPECT_THAT(s.error_message(), HasSubstr("neither served here nor archived"));
  for (const std::string& bad : std::vector<std::string>{"", "../default", std::string(300, 'x')}) {
    s = DeleteMap(bad, true);
    EXPECT_EQ(s.error_code(), grpc::StatusCode::INVALID_ARGUMENT) << bad;
    EXPECT_EQ(RestoreMap(bad).error_code(), grpc::StatusCode::INVALID_ARGUMENT) << bad;
  }
  EXPECT_EQ(RestoreMap("site-9").error_code(), grpc::StatusCode::NOT_FOUND);
  s = RestoreMap("site-7");
  EXPECT_EQ(s.error_code(), grpc::StatusCode::ALREADY_EXISTS);
  EXPECT_THAT(s.error_message(), HasSubstr("is served here"));
  // Nothing moved.
  EXPECT_EQ(ListMaps().maps_size(), 2);
  EXPECT_EQ(StoredBatches("site-7"), 6u);
  EXPECT_TRUE(std::filesystem::exists(dir_.File("default.db")));
  for (const pb::IngestAck& ack : Stream(Walk("r2", 2)))
    EXPECT_EQ(ack.result(), pb::IngestAck::STORED) << ack.message();
}

// One database (--db): no map to delete but the default.
TEST_F(ServerFixture, ASingleDatabaseDeletesNoMap) {
  grpc::ClientContext ctx;
  pb::DeleteMapRequest request;
  request.set_map_id("site-7");
  pb::DeleteMapResponse response;
  const grpc::Status s = stub_->DeleteMap(&ctx, request, &response);
  EXPECT_EQ(s.error_code(), grpc::StatusCode::FAILED_PRECONDITION);
  EXPECT_THAT(s.error_message(), HasSubstr("--data-dir"));
}

}  // namespace
}  // namespace mapd::testing
