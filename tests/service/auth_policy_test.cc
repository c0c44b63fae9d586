// The role table and the token format, without a server.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "service/auth.h"
#include "service/token.h"

namespace mapd::service {
namespace {

using ::testing::HasSubstr;

Principal Robot(const std::string& robot) {
  return {robot + "-key", Role::kRobot, robot, false, "", "", {}};
}

TEST(AuthorizeTest, RoleTableMatchesTheDocs) {
  struct Row {
    Permission p;
    bool reader, robot_own, op, admin;
  };
  const Row rows[] = {
      {Permission::kReadMap, true, true, true, true},
      {Permission::kReadSubmaps, true, true, true, true},
      {Permission::kWrite, false, true, true, true},
      {Permission::kDelete, false, true, true, true},
      {Permission::kMerge, false, false, true, true},
      {Permission::kReadAudit, false, false, true, true},
      {Permission::kManageTokens, false, false, false, true},
      {Permission::kManageMaps, false, false, false, true},
  };
  for (const Row& r : rows) {
    SCOPED_TRACE(PermissionName(r.p));
    EXPECT_EQ(Authorize({"x", Role::kReader, "", false, "", "", {}}, r.p, "A", "r1").ok(),
              r.reader);
    EXPECT_EQ(Authorize(Robot("r1"), r.p, "A", "r1").ok(), r.robot_own);
    EXPECT_EQ(Authorize({"x", Role::kOperator, "", false, "", "", {}}, r.p, "A", "r1").ok(), r.op);
    EXPECT_EQ(Authorize({"x", Role::kAdmin, "", false, "", "", {}}, r.p, "A", "r1").ok(), r.admin);
  }
}

TEST(AuthorizeTest, RobotIsConfinedToItsOwnRobotId) {
  for (Permission p : {Permission::kWrite, Permission::kDelete, Permission::kReadSubmaps}) {
    const Status s = Authorize(Robot("r1"), p, "UploadSubmap", "r2");
    EXPECT_EQ(s.code(), StatusCode::kPermissionDenied);
    EXPECT_THAT(s.message(), HasSubstr("role robot"));
    EXPECT_THAT(s.message(), HasSubstr("robot 'r2'"));
    EXPECT_THAT(s.message(), HasSubstr(PermissionName(p)));
  }
  EXPECT_TRUE(Authorize(Robot("r1"), Permission::kReadMap, "GetFeatureMap", "r2").ok());
}

TEST(AuthorizeTest, DenialNamesRoleAndPermission) {
  const Status s =
      Authorize({"dash", Role::kReader, "", false, "", "", {}}, Permission::kMerge, "MergeSubmaps");
  EXPECT_EQ(s.code(), StatusCode::kPermissionDenied);
  EXPECT_THAT(s.message(), HasSubstr("'dash' (role reader)"));
  EXPECT_THAT(s.message(), HasSubstr("permission merge (granted to operator, admin)"));
}

TEST(AuthorizeTest, AnonymousMayDoAllButManageTokens) {
  Principal anon{"anonymous", Role::kOperator, "", true, "", "", {}};
  EXPECT_TRUE(Authorize(anon, Permission::kWrite, "Ingest", "anything").ok());
  EXPECT_EQ(Authorize(anon, Permission::kManageTokens, "CreateToken").code(),
            StatusCode::kPermissionDenied);
  // The open mode is loopback without tokens: making a map is no escalation.
  EXPECT_TRUE(Authorize(anon, Permission::kManageMaps, "CreateMap").ok());
}

TEST(TokenTest, ParsesTheWireFormatAndRefusesOthers) {
  int64_t id = 0;
  std::string secret;
  ASSERT_TRUE(ParseToken("mapd_42_abcDEF-_", &id, &secret).ok());
  EXPECT_EQ(id, 42);
  EXPECT_EQ(secret, "abcDEF-_");
  for (const char* bad : {"", "mapd_", "mapd__x", "mapd_42", "mapd_42_", "mapd_4x_y", "tok_1_x",
                          "mapd_1234567890123456789_x"}) {
    EXPECT_FALSE(ParseToken(bad, &id, &secret).ok()) << bad;
  }
}

TEST(TokenTest, Sha256AndConstantTimeEqual) {
  // FIPS 180-2 test vector "abc".
  const std::string h = Sha256("abc");
  ASSERT_EQ(h.size(), 32u);
  EXPECT_EQ(static_cast<unsigned char>(h[0]), 0xba);
  EXPECT_EQ(static_cast<unsigned char>(h[31]), 0xad);
  EXPECT_TRUE(ConstantTimeEqual(h, Sha256("abc")));
  EXPECT_FALSE(ConstantTimeEqual(h, Sha256("abd")));
  EXPECT_FALSE(ConstantTimeEqual(h, h.substr(1)));
}

}  // namespace
}  // namespace mapd::service
