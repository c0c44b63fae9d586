// Submaps with identities: a robot uploads, reads and deletes only its own;
// another robot can neither squat its names nor delete or read its maps; an
// operator can. Everything written or refused is in the audit log. The reads
// of the map and of merges (WatchFeatureMap, GetGlobalMap, ListMerges,
// GetMerge) need a token and serve every role the whole map.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "common/octomap_scenes.h"
#include "service/support/auth_fixture.h"
#include "watch_client.h"

namespace mapd::testing {
namespace {

using ::testing::HasSubstr;

class AuthSubmapTest : public AuthFixture {
 protected:
  grpc::Status Upload(const std::string& token, const std::string& robot, const std::string& name,
                      const std::string& bytes, pb::SubmapInfo* info) {
    auto ctx = As(token);
    auto writer = stub_->UploadSubmap(ctx.get(), info);
    pb::UploadSubmapRequest m;
    m.mutable_header()->set_robot_id(robot);
    m.mutable_header()->set_name(name);
    m.mutable_header()->set_format(pb::SUBMAP_FORMAT_OCTOMAP_BT);
    bool open = writer->Write(m);
    m.set_chunk(bytes);
    if (open) open = writer->Write(m);
    if (open) writer->WritesDone();
    return writer->Finish();
  }
  grpc::StatusCode Delete(const std::string& token, uint64_t id) {
    auto ctx = As(token);
    pb::DeleteSubmapRequest request;
    request.set_id(id);
    pb::DeleteSubmapResponse r;
    return stub_->DeleteSubmap(ctx.get(), request, &r).error_code();
  }
  grpc::StatusCode Get(const std::string& token, uint64_t id) {
    auto ctx = As(token);
    pb::GetSubmapRequest request;
    request.set_id(id);
    auto reader = stub_->GetSubmap(ctx.get(), request);
    pb::DataChunk chunk;
    while (reader->Read(&chunk)) {
    }
    return reader->Finish().error_code();
  }
  // GetSubmap (id != 0) or GetGlobalMap (id == 0): the bytes.
  grpc::Status GetSubmapBytes(const std::string& token, uint64_t id, std::string* bytes) {
    auto ctx = As(token);
    pb::GetSubmapRequest request;
    request.set_id(id);
    auto reader = id != 0 ? stub_->GetSubmap(ctx.get(), request)
                          : stub_->GetGlobalMap(ctx.get(), pb::GetGlobalMapRequest());
    pb::DataChunk chunk;
    bytes->clear();
    while (reader->Read(&chunk)) *bytes += chunk.data();
    return reader->Finish();
  }
  grpc::Status ListMerges(const std::string& token, pb::ListMergesResponse* response) {
    auto ctx = As(token);
    return stub_->ListMerges(ctx.get(), pb::ListMergesRequest(), response);
  }
  grpc::Status GetMerge(const std::string& token, uint64_t id, pb::MergeRecord* record) {
    auto ctx = As(token);
    pb::GetMergeRequest request;
    request.set_id(id);
    return stub_->GetMerge(ctx.get(), request, record);
  }
  int Submaps() {
    auto ctx = As(admin_);
    pb::ListSubmapsResponse r;
    EXPECT_TRUE(stub_->ListSubmaps(ctx.get(), {}, &r).ok());
    return r.submaps_size();
  }
  std::string admin_;
};

TEST_F(AuthSubmapTest, RobotsOwnTheirSubmaps) {
  admin_ = OfflineToken(service::Role::kAdmin, "root");
  const std::string r1 = ApiToken(admin_, pb::ROLE_ROBOT, "r1-key", "r1");
  const std::string r2 = ApiToken(admin_, pb::ROLE_ROBOT, "r2-key", "r2");
  const std::string op = ApiToken(admin_, pb::ROLE_OPERATOR, "alice");
  const std::string bytes = RoomSubmap(RoomScene{}, 0.0, 6.0, Eigen::Isometry3d::Identity());

  pb::SubmapInfo info;
  ASSERT_TRUE(Upload(r1, "r1", "room", bytes, &info).ok());
  const uint64_t id = info.id();
  // r2 cannot squat r1's name space (nor overwrite: names are unique per robot).
  pb::SubmapInfo squat;
  const grpc::Status s = Upload(r2, "r1", "hall", bytes, &squat);
  EXPECT_EQ(s.error_code(), grpc::StatusCode::PERMISSION_DENIED);
  EXPECT_THAT(s.error_message(), HasSubstr("role robot"));
  EXPECT_EQ(Submaps(), 1);

  EXPECT_EQ(Get(r2, id), grpc::StatusCode::PERMISSION_DENIED);
  EXPECT_EQ(Get(r1, id), grpc::StatusCode::OK);
  EXPECT_EQ(Delete(r2, id), grpc::StatusCode::PERMISSION_DENIED);
  EXPECT_EQ(Submaps(), 1) << "a refused delete deletes nothing";
  EXPECT_EQ(Delete(op, id), grpc::StatusCode::OK);
  EXPECT_EQ(Submaps(), 0);
  ASSERT_TRUE(Upload(r1, "r1", "room2", bytes, &info).ok());
  EXPECT_EQ(Delete(r1, info.id()), grpc::StatusCode::OK) << "a robot deletes its own";

  std::vector<std::string> seen;
  for (const pb::AuditEntry& e : Audit(admin_))
    seen.push_back(e.who() + " " + e.action() + " " + e.result().substr(0, 6));
  EXPECT_THAT(seen, ::testing::IsSupersetOf({"r1-key UploadSubmap ok", "r2-key UploadSubmap denied",
                                             "r2-key DeleteSubmap denied", "alice DeleteSubmap ok",
                                             "r1-key DeleteSubmap ok"}));
}

// docs/security.md: read_map (WatchFeatureMap, GetGlobalMap, ListMerges,
// GetMerge) is every role's, a robot's too, without a robot scope: a robot
// token sees the whole map, the other robot's walls and merges included. No
// token, or a revoked one, is UNAUTHENTICATED.
TEST_F(AuthSubmapTest, MapAndMergeReadsNeedATokenAndShowEveryRoleTheWholeMap) {
  admin_ = OfflineToken(service::Role::kAdmin, "root");
  const std::string reader = ApiToken(admin_, pb::ROLE_READER, "dashboard");
  const std::string r1 = ApiToken(admin_, pb::ROLE_ROBOT, "r1-key", "r1");
  const std::string r2 = ApiToken(admin_, pb::ROLE_ROBOT, "r2-key", "r2");
  const std::string op = ApiToken(admin_, pb::ROLE_OPERATOR, "alice");
  const std::string gone = ApiToken(admin_, pb::ROLE_OPERATOR, "bob");
  {
    auto ctx = As(admin_);
    pb::ListTokensResponse tokens;
    ASSERT_TRUE(stub_->ListTokens(ctx.get(), {}, &tokens).ok());
    pb::RevokeTokenRequest revoke;
    for (const pb::TokenInfo& t : tokens.tokens()) {
      if (t.name() == "bob") revoke.set_id(t.id());
    }
    ASSERT_NE(revoke.id(), 0u);
    auto ctx2 = As(admin_);
    pb::RevokeTokenResponse revoked;
    ASSERT_TRUE(stub_->RevokeToken(ctx2.get(), revoke, &revoked).ok());
  }

  // Both robots map the room with their own tokens; each uploads its half and
  // an operator merges them.
  grpc::Status s;
  ASSERT_EQ(StreamAs(r1, Walk("r1", 6), &s).size(), 6u);
  ASSERT_TRUE(s.ok()) << s.error_message();
  ASSERT_EQ(StreamAs(r2, Walk("r2", 6), &s).size(), 6u);
  ASSERT_TRUE(s.ok()) << s.error_message();
  const RoomScene scene;
  const Eigen::Isometry3d T_map_b = YawTranslation(M_PI / 2, Eigen::Vector3d(2.0, -1.0, 0.0));
  pb::SubmapInfo west, east;
  ASSERT_TRUE(
      Upload(r1, "r1", "west", RoomSubmap(scene, 0, 8, Eigen::Isometry3d::Identity()), &west).ok());
  ASSERT_TRUE(Upload(r2, "r2", "east", RoomSubmap(scene, 2, 10, T_map_b), &east).ok());
  pb::MergeResult merged;
  {
    auto ctx = As(op);
    pb::MergeSubmapsRequest request;
    request.add_submap_ids(west.id());
    request.add_submap_ids(east.id());
    auto reader_stream = stub_->MergeSubmaps(ctx.get(), request);
    pb::MergeProgress p;
    while (reader_stream->Read(&p)) {
      if (p.has_result()) merged = p.result();
    }
    const grpc::Status m = reader_stream->Finish();
    ASSERT_TRUE(m.ok()) << m.error_message();
    ASSERT_NE(merged.merge_id(), 0u);
  }
  std::string merged_bytes;
  ASSERT_EQ(GetSubmapBytes(admin_, merged.merged_submap_id(), &merged_bytes).error_code(),
            grpc::StatusCode::OK);
  ASSERT_FALSE(merged_bytes.empty());

  struct Caller {
    const char* who;
    std::string token;
  };
  const std::vector<Caller> refused = {{"no token", ""}, {"a revoked token", gone}};
  const std::vector<Caller> allowed = {
      {"reader", reader}, {"robot r1", r1}, {"robot r2", r2}, {"operator", op}, {"admin", admin_}};

  for (const Caller& c : refused) {
    SCOPED_TRACE(c.who);
    WatchClient watch(stub_.get(), {}, /*read=*/true, c.token);
    ASSERT_TRUE(watch.WaitFor([&] { return watch.done_; }, std::chrono::seconds(30)))
        << "the watch was served";
    const grpc::Status w = watch.Finish();
    EXPECT_EQ(w.error_code(), grpc::StatusCode::UNAUTHENTICATED) << w.error_message();
    EXPECT_TRUE(watch.Messages().empty()) << "no map before the refusal";
    std::string bytes;
    EXPECT_EQ(GetSubmapBytes(c.token, 0, &bytes).error_code(), grpc::StatusCode::UNAUTHENTICATED);
    EXPECT_TRUE(bytes.empty());
    pb::ListMergesResponse list;
    EXPECT_EQ(ListMerges(c.token, &list).error_code(), grpc::StatusCode::UNAUTHENTICATED);
    EXPECT_EQ(list.merges_size(), 0);
    pb::MergeRecord record;
    EXPECT_EQ(GetMerge(c.token, merged.merge_id(), &record).error_code(),
              grpc::StatusCode::UNAUTHENTICATED);
    EXPECT_EQ(record.id(), 0u);
  }

  for (const Caller& c : allowed) {
    SCOPED_TRACE(c.who);
    // The whole fused map: four walls, each seen by both robots.
    WatchClient watch(stub_.get(), {}, /*read=*/true, c.token);
    ASSERT_TRUE(watch.WaitFor([&] { return !watch.messages_.empty() || watch.done_; }));
    const std::vector<pb::FeatureMapDelta> messages = watch.Messages();
    ASSERT_FALSE(messages.empty()) << watch.Finish().error_message();
    EXPECT_TRUE(messages[0].resync());
    ASSERT_EQ(messages[0].added_size(), 4);
    for (const pb::FusedFeature& f : messages[0].added())
      EXPECT_THAT(f.robots(), ::testing::ElementsAre("r1", "r2"));
    watch.Cancel();
    EXPECT_EQ(watch.Finish().error_code(), grpc::StatusCode::CANCELLED);

    // The global map is the merged map, both robots' halves.
    std::string bytes;
    const grpc::Status g = GetSubmapBytes(c.token, 0, &bytes);
    EXPECT_TRUE(g.ok()) << g.error_message();
    EXPECT_EQ(bytes.size(), merged_bytes.size());
    EXPECT_TRUE(bytes == merged_bytes) << "the global map is not the merged map";

    pb::ListMergesResponse list;
    const grpc::Status l = ListMerges(c.token, &list);
    ASSERT_TRUE(l.ok()) << l.error_message();
    ASSERT_EQ(list.merges_size(), 1);
    EXPECT_EQ(list.merges(0).id(), merged.merge_id());
    EXPECT_EQ(list.merges(0).state(), pb::MERGE_STATE_ACCEPTED);
    EXPECT_EQ(list.merges(0).requested_by(), "alice");
    ASSERT_EQ(list.merges(0).inputs_size(), 2);
    EXPECT_EQ(list.merges(0).inputs(0).submap_id(), west.id());
    EXPECT_EQ(list.merges(0).inputs(1).submap_id(), east.id());

    pb::MergeRecord record;
    const grpc::Status r = GetMerge(c.token, merged.merge_id(), &record);
    ASSERT_TRUE(r.ok()) << r.error_message();
    EXPECT_EQ(record.id(), merged.merge_id());
    EXPECT_EQ(record.merged_submap_id(), merged.merged_submap_id());
    ASSERT_EQ(record.inputs_size(), 2);
    EXPECT_GE(record.inputs(1).matched_size(), 4) << "GetMerge carries the corner pairs";
    EXPECT_EQ(GetMerge(c.token, merged.merge_id() + 1, &record).error_code(),
              grpc::StatusCode::NOT_FOUND);
  }

  // The line read_map draws: the merged map is no robot's submap, so a robot
  // reads it as the global map but not through GetSubmap (read_submaps, own
  // robot only).
  std::string bytes;
  const grpc::Status own = GetSubmapBytes(r1, merged.merged_submap_id(), &bytes);
  EXPECT_EQ(own.error_code(), grpc::StatusCode::PERMISSION_DENIED) << own.error_message();
  EXPECT_THAT(own.error_message(), HasSubstr("role robot"));
  EXPECT_THAT(own.error_message(), HasSubstr("read_submaps"));
}

}  // namespace
}  // namespace mapd::testing
