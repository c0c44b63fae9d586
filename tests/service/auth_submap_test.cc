// Submaps with identities: a robot uploads, reads and deletes only its own;
// another robot can neither squat its names nor delete or read its maps; an
// operator can. Everything written or refused is in the audit log.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "common/octomap_scenes.h"
#include "service/support/auth_fixture.h"

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

}  // namespace
}  // namespace mapd::testing
