// Merge records and review mode against a real in-process server
// (submap_service.h, "Review"): a reviewed merge is PROPOSED and changes
// nothing until ApproveMerge; RejectMerge ends it without effect; records
// outlive restarts; approvals of stale or conflicting proposals are refused
// with the reason; only operators and admins decide, and decisions are audited.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <string>
#include <vector>

#include "common/octomap_scenes.h"
#include "service/support/auth_fixture.h"

namespace mapd::testing {
namespace {

using ::testing::ElementsAre;
using ::testing::HasSubstr;

class MergeReviewTest : public AuthFixture {
 protected:
  // Uploads `bytes` as robot/name in `session` ("" = none); returns the id (0 on failure).
  uint64_t Upload(const std::string& robot, const std::string& name, const std::string& bytes,
                  const std::string& session = "s1", const std::string& token = "") {
    auto ctx = As(token);
    pb::SubmapInfo info;
    auto writer = stub_->UploadSubmap(ctx.get(), &info);
    pb::UploadSubmapRequest m;
    pb::SubmapHeader* h = m.mutable_header();
    h->set_robot_id(robot);
    h->set_name(name);
    h->set_format(pb::SUBMAP_FORMAT_OCTOMAP_BT);
    h->set_session_id(session);
    EXPECT_TRUE(writer->Write(m));
    m.set_chunk(bytes);
    EXPECT_TRUE(writer->Write(m));
    writer->WritesDone();
    const grpc::Status s = writer->Finish();
    EXPECT_TRUE(s.ok()) << s.error_message();
    return s.ok() ? info.id() : 0;
  }

  // MergeSubmaps to its end: the result (merge_id 0 if none) and the status.
  pb::MergeResult Merge(const std::vector<uint64_t>& ids, bool review,
                        grpc::Status* status = nullptr, const std::string& token = "") {
    auto ctx = As(token);
    pb::MergeSubmapsRequest request;
    for (uint64_t id : ids) request.add_submap_ids(id);
    request.set_review(review);
    auto reader = stub_->MergeSubmaps(ctx.get(), request);
    pb::MergeProgress p;
    pb::MergeResult result;
    while (reader->Read(&p)) {
      if (p.has_result()) result = p.result();
    }
    const grpc::Status s = reader->Finish();
    if (status != nullptr)
      *status = s;
    else
      EXPECT_TRUE(s.ok()) << s.error_message();
    return result;
  }

  grpc::Status Get(uint64_t id, pb::MergeRecord* out, const std::string& token = "") {
    auto ctx = As(token);
    pb::GetMergeRequest request;
    request.set_id(id);
    return stub_->GetMerge(ctx.get(), request, out);
  }
  pb::MergeRecord GetOk(uint64_t id) {
    pb::MergeRecord r;
    const grpc::Status s = Get(id, &r);
    EXPECT_TRUE(s.ok()) << s.error_message();
    return r;
  }
  std::vector<pb::MergeRecord> List(pb::MergeState state = pb::MERGE_STATE_UNSPECIFIED,
                                    const std::string& token = "") {
    auto ctx = As(token);
    pb::ListMergesRequest request;
    request.set_state(state);
    pb::ListMergesResponse response;
    const grpc::Status s = stub_->ListMerges(ctx.get(), request, &response);
    EXPECT_TRUE(s.ok()) << s.error_message();
    return {response.merges().begin(), response.merges().end()};
  }
  grpc::Status Approve(uint64_t id, pb::MergeRecord* out = nullptr, const std::string& token = "") {
    auto ctx = As(token);
    pb::ApproveMergeRequest request;
    request.set_id(id);
    pb::MergeRecord record;
    const grpc::Status s = stub_->ApproveMerge(ctx.get(), request, &record);
    if (out != nullptr) *out = record;
    return s;
  }
  grpc::Status Reject(uint64_t id, const std::string& reason, pb::MergeRecord* out = nullptr,
                      const std::string& token = "") {
    auto ctx = As(token);
    pb::RejectMergeRequest request;
    request.set_id(id);
    request.set_reason(reason);
    pb::MergeRecord record;
    const grpc::Status s = stub_->RejectMerge(ctx.get(), request, &record);
    if (out != nullptr) *out = record;
    return s;
  }
  // GetGlobalMap's status; *members gets the submaps it holds.
  grpc::Status GlobalMap(std::vector<uint64_t>* members = nullptr) {
    grpc::ClientContext ctx;
    auto reader = stub_->GetGlobalMap(&ctx, {});
    pb::DataChunk chunk;
    bool first = true;
    while (reader->Read(&chunk)) {
      if (first && members != nullptr) {
        members->clear();
        for (const auto& m : chunk.global().members()) members->push_back(m.submap_id());
      }
      first = false;
    }
    return reader->Finish();
  }
  uint64_t GlobalMapVersion() {
    grpc::ClientContext ctx;
    auto reader = stub_->GetGlobalMap(&ctx, {});
    pb::DataChunk chunk;
    uint64_t version = 0;
    while (reader->Read(&chunk)) {
      if (chunk.has_global()) version = chunk.global().version();
    }
    EXPECT_TRUE(reader->Finish().ok());
    return version;
  }
  std::string GlobalMapBytes() {
    grpc::ClientContext ctx;
    auto reader = stub_->GetGlobalMap(&ctx, {});
    pb::DataChunk chunk;
    std::string bytes;
    while (reader->Read(&chunk)) bytes += chunk.data();
    EXPECT_TRUE(reader->Finish().ok());
    return bytes;
  }
  bool Tied(const std::string& robot) {
    grpc::ClientContext ctx;
    pb::ListRobotsResponse robots;
    EXPECT_TRUE(stub_->ListRobots(&ctx, {}, &robots).ok());
    for (const auto& r : robots.robots()) {
      if (r.robot_id() == robot) return r.frame_tied();
    }
    return false;
  }
  // The robots of every fused wall, e.g. {"r1"} before a tie, {"r1", "r2"} after.
  std::vector<std::vector<std::string>> WallRobots() {
    std::vector<std::vector<std::string>> out;
    for (const auto& f : Features()) out.emplace_back(f.robots().begin(), f.robots().end());
    return out;
  }

  // r1 localised (map frame), r2 in its own frame; their submaps a (west) and b (east).
  void TwoRobotsAndTheirSubmaps() {
    Stream(Walk("r1", 6));
    Stream(InFrame(Walk("r2", 6), T_map_b_));
    a_ = Upload("r1", "west", RoomSubmap(scene_, 0, 8, Eigen::Isometry3d::Identity()));
    b_ = Upload("r2", "east", East());
    ASSERT_NE(a_, 0u);
    ASSERT_NE(b_, 0u);
  }
  std::string East() const { return RoomSubmap(scene_, 2, 10, T_map_b_); }

  RoomScene scene_;
  const Eigen::Isometry3d T_map_b_ = YawTranslation(M_PI / 2, Eigen::Vector3d(2.0, -1.0, 0.0));
  uint64_t a_ = 0, b_ = 0;
};

const std::vector<std::string> kR1 = {"r1"}, kBoth = {"r1", "r2"};

TEST_F(MergeReviewTest, ReviewedMergeChangesNothingUntilApproved) {
  TwoRobotsAndTheirSubmaps();
  const pb::MergeResult proposed = Merge({a_, b_}, /*review=*/true);
  ASSERT_NE(proposed.merge_id(), 0u);
  EXPECT_EQ(proposed.state(), pb::MERGE_STATE_PROPOSED);
  ASSERT_EQ(proposed.alignments_size(), 2);

  // Proposed: frames untied, r2's walls not fused, the global map only r1's
  // submap (uploaded in the map frame); the merged map is stored (for
  // rendering) and the record says who asked.
  EXPECT_FALSE(Tied("r2"));
  EXPECT_THAT(WallRobots(), ElementsAre(kR1, kR1, kR1, kR1));
  std::vector<uint64_t> members;
  ASSERT_TRUE(GlobalMap(&members).ok());
  EXPECT_THAT(members, ElementsAre(a_));
  pb::MergeRecord r = GetOk(proposed.merge_id());
  EXPECT_EQ(r.state(), pb::MERGE_STATE_PROPOSED);
  EXPECT_EQ(r.requested_by(), "anonymous");
  EXPECT_GT(r.created_ns(), 0);
  EXPECT_EQ(r.decided_ns(), 0);
  EXPECT_EQ(r.merged_submap_id(), proposed.merged_submap_id());
  ASSERT_EQ(r.inputs_size(), 2);
  EXPECT_EQ(r.inputs(1).submap_id(), b_);
  EXPECT_GE(r.inputs(1).matched_corners(), 4u);
  EXPECT_NEAR(r.inputs(1).t_reference_submap().translation().x(),
              proposed.alignments(1).t_reference_submap().translation().x(), 1e-9);
  EXPECT_EQ(List(pb::MERGE_STATE_PROPOSED).size(), 1u);
  EXPECT_TRUE(List(pb::MERGE_STATE_ACCEPTED).empty());

  // Approved: in effect, as an accepted merge would have been.
  pb::MergeRecord approved;
  const grpc::Status s = Approve(proposed.merge_id(), &approved);
  ASSERT_TRUE(s.ok()) << s.error_message();
  EXPECT_EQ(approved.state(), pb::MERGE_STATE_ACCEPTED);
  EXPECT_EQ(approved.decided_by(), "anonymous");
  EXPECT_GE(approved.decided_ns(), approved.created_ns());
  EXPECT_TRUE(Tied("r2"));
  EXPECT_THAT(WallRobots(), ElementsAre(kBoth, kBoth, kBoth, kBoth));
  ASSERT_TRUE(GlobalMap(&members).ok());
  EXPECT_THAT(members, ElementsAre(a_, b_));  // r2's submap joined

  // Decided once only, with the state named.
  grpc::Status again = Approve(proposed.merge_id());
  EXPECT_EQ(again.error_code(), grpc::StatusCode::FAILED_PRECONDITION);
  EXPECT_THAT(again.error_message(), HasSubstr("is accepted"));
  again = Reject(proposed.merge_id(), "too late");
  EXPECT_EQ(again.error_code(), grpc::StatusCode::FAILED_PRECONDITION);
  EXPECT_THAT(again.error_message(), HasSubstr("is accepted"));

  Restart();
  r = GetOk(proposed.merge_id());
  EXPECT_EQ(r.state(), pb::MERGE_STATE_ACCEPTED);
  EXPECT_EQ(r.decided_ns(), approved.decided_ns());
  EXPECT_THAT(WallRobots(), ElementsAre(kBoth, kBoth, kBoth, kBoth));
}

// The matched corners behind a merge are served by GetMerge (not ListMerges),
// survive a restart, and the stored transform maps each input's corners onto
// their partners in the reference frame: their RMS distance is within the
// residual gate (merge.max_residual_voxels of the coarser map).
TEST_F(MergeReviewTest, GetMergeServesMatchedCornersThatTheTransformMapsOntoEachOther) {
  TwoRobotsAndTheirSubmaps();
  const pb::MergeResult proposed = Merge({a_, b_}, /*review=*/true);
  ASSERT_NE(proposed.merge_id(), 0u);
  EXPECT_EQ(proposed.alignments(1).matched_size(), 0);  // MergeResult leaves them out

  auto check = [&](const pb::MergeRecord& r) {
    ASSERT_EQ(r.inputs_size(), 2);
    EXPECT_EQ(r.inputs(0).matched_size(), 0);  // the reference
    const pb::SubmapAlignment& b = r.inputs(1);
    ASSERT_GE(b.matched_corners(), 4u);
    ASSERT_EQ(static_cast<uint32_t>(b.matched_size()), b.matched_corners());
    // The rest of the evidence is stored with them (and survives a restart).
    EXPECT_EQ(b.source(), proposed.alignments(1).source());
    EXPECT_FALSE(b.source().empty());
    EXPECT_EQ(b.support_fraction(), proposed.alignments(1).support_fraction());
    EXPECT_GT(b.support_fraction(), 0.05);
    EXPECT_TRUE(r.inputs(0).source().empty());
    const pb::Rigid3& T = b.t_reference_submap();
    const Eigen::Isometry3d T_ref_b =
        Eigen::Translation3d(T.translation().x(), T.translation().y(), T.translation().z()) *
        Eigen::Quaterniond(T.rotation().w(), T.rotation().x(), T.rotation().y(), T.rotation().z());
    double sum_sq = 0;
    for (const pb::MatchedCorner& c : b.matched()) {
      const Eigen::Vector3d in_b(c.in_submap().x(), c.in_submap().y(), c.in_submap().z());
      const Eigen::Vector3d in_ref(c.in_reference().x(), c.in_reference().y(),
                                   c.in_reference().z());
      // The submap's corners lie in the room (map frame) after T_map_b_.
      EXPECT_LT((T_ref_b * in_b - T_map_b_ * in_b).norm(), scene_.resolution_m);
      sum_sq += (T_ref_b * in_b - in_ref).squaredNorm();
    }
    const double rms = std::sqrt(sum_sq / b.matched_size());
    EXPECT_LE(rms, 0.75 * scene_.resolution_m);  // merge.max_residual_voxels' default
  };
  check(GetOk(proposed.merge_id()));
  const std::vector<pb::MergeRecord> listed = List();
  ASSERT_EQ(listed.size(), 1u);
  EXPECT_EQ(listed[0].inputs(1).matched_size(), 0);  // ListMerges stays small
  EXPECT_GE(listed[0].inputs(1).matched_corners(), 4u);
  Restart();
  check(GetOk(proposed.merge_id()));
}

TEST_F(MergeReviewTest, ServerSettingMakesReviewTheDefaultAndRejectionHasNoEffect) {
  config_.submaps.merge_review = true;
  Restart();
  TwoRobotsAndTheirSubmaps();
  const pb::MergeResult proposed = Merge({a_, b_}, /*review=*/false);
  ASSERT_EQ(proposed.state(), pb::MERGE_STATE_PROPOSED);

  EXPECT_EQ(Reject(proposed.merge_id(), "").error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_EQ(Reject(proposed.merge_id(), std::string(1001, 'x')).error_code(),
            grpc::StatusCode::INVALID_ARGUMENT);
  // A reason is one line: a newline or an ESC would forge rows in
  // `mapctl merges` and `mapctl audit` (issue 43).
  for (const char* forged : {"fine\n7  accepted  1,2", "\x1b[2Jfine", "fine\r"}) {
    const grpc::Status s = Reject(proposed.merge_id(), forged);
    EXPECT_EQ(s.error_code(), grpc::StatusCode::INVALID_ARGUMENT) << forged;
    EXPECT_THAT(s.error_message(), HasSubstr("control characters"));
  }
  pb::MergeRecord rejected;
  ASSERT_TRUE(Reject(proposed.merge_id(), "walls askew in the picture", &rejected).ok());
  EXPECT_EQ(rejected.state(), pb::MERGE_STATE_REJECTED);
  EXPECT_EQ(rejected.reason(), "walls askew in the picture");
  const grpc::Status approve = Approve(proposed.merge_id());
  EXPECT_EQ(approve.error_code(), grpc::StatusCode::FAILED_PRECONDITION);
  EXPECT_THAT(approve.error_message(), HasSubstr("is rejected"));
  EXPECT_FALSE(Tied("r2"));
  std::vector<uint64_t> members;
  ASSERT_TRUE(GlobalMap(&members).ok());
  EXPECT_THAT(members, ElementsAre(a_));  // the rejected proposal placed nothing

  Restart();
  const std::vector<pb::MergeRecord> all = List();
  ASSERT_EQ(all.size(), 1u);
  EXPECT_EQ(all[0].state(), pb::MERGE_STATE_REJECTED);
  EXPECT_EQ(all[0].reason(), "walls askew in the picture");
  EXPECT_EQ(all[0].decided_by(), "anonymous");
  EXPECT_THAT(WallRobots(), ElementsAre(kR1, kR1, kR1, kR1));
  // A rejected merge pins nothing: its input can go.
  grpc::ClientContext ctx;
  pb::DeleteSubmapRequest del;
  del.set_id(b_);
  pb::DeleteSubmapResponse deleted;
  EXPECT_TRUE(stub_->DeleteSubmap(&ctx, del, &deleted).ok());
}

// A submap uploaded in a session whose frame is tied (here: a localised
// robot's) is in the global map at once; deleting it rebuilds the map
// without it, and the versions count every change.
TEST_F(MergeReviewTest, SubmapsUploadedInTheMapFrameAreGlobalUntilDeleted) {
  Stream(Walk("r1", 6));
  a_ = Upload("r1", "west", RoomSubmap(scene_, 0, 8, Eigen::Isometry3d::Identity()));
  std::vector<uint64_t> members;
  ASSERT_TRUE(GlobalMap(&members).ok());
  EXPECT_THAT(members, ElementsAre(a_));
  const std::string v1 = GlobalMapBytes();
  const uint64_t more =
      Upload("r1", "more", RoomSubmap(scene_, 4, 10, Eigen::Isometry3d::Identity()));
  ASSERT_TRUE(GlobalMap(&members).ok());
  EXPECT_THAT(members, ElementsAre(a_, more));
  EXPECT_EQ(GlobalMapVersion(), 2u);

  grpc::ClientContext ctx;
  pb::DeleteSubmapRequest del;
  del.set_id(more);
  pb::DeleteSubmapResponse deleted;
  ASSERT_TRUE(stub_->DeleteSubmap(&ctx, del, &deleted).ok());
  ASSERT_TRUE(GlobalMap(&members).ok());
  EXPECT_THAT(members, ElementsAre(a_));
  EXPECT_EQ(GlobalMapVersion(), 3u);
  EXPECT_TRUE(GlobalMapBytes() == v1) << "the rebuilt map is not the map of its one member";
}

TEST_F(MergeReviewTest, UnknownAndMissingIdsAreClearErrors) {
  pb::MergeRecord r;
  EXPECT_EQ(Get(0, &r).error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_EQ(Get(42, &r).error_code(), grpc::StatusCode::NOT_FOUND);
  EXPECT_EQ(Approve(0).error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  const grpc::Status approve = Approve(42);
  EXPECT_EQ(approve.error_code(), grpc::StatusCode::NOT_FOUND);
  EXPECT_THAT(approve.error_message(), HasSubstr("no merge with id 42"));
  EXPECT_EQ(Reject(42, "why").error_code(), grpc::StatusCode::NOT_FOUND);
  EXPECT_TRUE(List().empty());
  auto ctx = As("");
  pb::ListMergesRequest bad;
  bad.set_state(static_cast<pb::MergeState>(17));
  pb::ListMergesResponse response;
  EXPECT_EQ(stub_->ListMerges(ctx.get(), bad, &response).error_code(),
            grpc::StatusCode::INVALID_ARGUMENT);
}

TEST_F(MergeReviewTest, RefusedMergeIsListedWithItsReasonAndCannotBeApproved) {
  TwoRobotsAndTheirSubmaps();
  RoomScene floor;
  floor.size_x_m = 4.0;
  floor.size_y_m = 4.0;
  floor.floor_only = true;
  const uint64_t bare =
      Upload("r3", "floor", RoomSubmap(floor, 0, 4, Eigen::Isometry3d::Identity()), "");
  grpc::Status status;
  Merge({a_, bare}, /*review=*/true, &status);
  ASSERT_EQ(status.error_code(), grpc::StatusCode::FAILED_PRECONDITION);
  const std::vector<pb::MergeRecord> all = List(pb::MERGE_STATE_REFUSED);
  ASSERT_EQ(all.size(), 1u);
  EXPECT_FALSE(all[0].reason().empty());
  EXPECT_EQ(all[0].merged_submap_id(), 0u);
  EXPECT_FALSE(all[0].inputs(1).has_t_reference_submap());
  const grpc::Status approve = Approve(all[0].id());
  EXPECT_EQ(approve.error_code(), grpc::StatusCode::FAILED_PRECONDITION);
  EXPECT_THAT(approve.error_message(), HasSubstr("is refused"));
}

TEST_F(MergeReviewTest, ApprovalIsRefusedOnceAnInputIsDeletedOrALaterMergeFixedTheFrames) {
  TwoRobotsAndTheirSubmaps();
  // A proposal whose input is deleted meanwhile (a proposal pins nothing).
  const pb::MergeResult stale = Merge({a_, b_}, /*review=*/true);
  ASSERT_EQ(stale.state(), pb::MERGE_STATE_PROPOSED);
  grpc::ClientContext ctx;
  pb::DeleteSubmapRequest del;
  del.set_id(b_);
  pb::DeleteSubmapResponse deleted;
  ASSERT_TRUE(stub_->DeleteSubmap(&ctx, del, &deleted).ok());
  grpc::Status s = Approve(stale.merge_id());
  EXPECT_EQ(s.error_code(), grpc::StatusCode::FAILED_PRECONDITION);
  EXPECT_THAT(s.error_message(), HasSubstr("input submap " + std::to_string(b_)));
  EXPECT_THAT(s.error_message(), HasSubstr("deleted"));
  EXPECT_EQ(GetOk(stale.merge_id()).state(), pb::MERGE_STATE_PROPOSED);

  // A proposal overtaken by a merge accepted since, on the same robot frame.
  const uint64_t b2 = Upload("r2", "east-again", East());
  const pb::MergeResult overtaken = Merge({a_, b2}, /*review=*/true);
  ASSERT_EQ(overtaken.state(), pb::MERGE_STATE_PROPOSED);
  const pb::MergeResult direct = Merge({a_, b2}, /*review=*/false);
  ASSERT_EQ(direct.state(), pb::MERGE_STATE_ACCEPTED);
  EXPECT_TRUE(Tied("r2"));
  s = Approve(overtaken.merge_id());
  EXPECT_EQ(s.error_code(), grpc::StatusCode::FAILED_PRECONDITION);
  EXPECT_THAT(s.error_message(),
              HasSubstr("merge " + std::to_string(direct.merge_id()) + ", accepted since"));
  EXPECT_EQ(GetOk(overtaken.merge_id()).state(), pb::MERGE_STATE_PROPOSED);
  EXPECT_TRUE(Reject(overtaken.merge_id(), "overtaken").ok());
}

TEST_F(MergeReviewTest, ReadersListOperatorsDecideAndDecisionsAreAudited) {
  const std::string admin = OfflineToken(service::Role::kAdmin, "root");
  const std::string op = ApiToken(admin, pb::ROLE_OPERATOR, "alice");
  const std::string reader = ApiToken(admin, pb::ROLE_READER, "dash");
  const std::string robot = ApiToken(admin, pb::ROLE_ROBOT, "r1-key", "r1");
  const uint64_t a =
      Upload("r1", "west", RoomSubmap(scene_, 0, 8, Eigen::Isometry3d::Identity()), "", op);
  const uint64_t b = Upload("r2", "east", East(), "", op);
  grpc::Status status;
  const pb::MergeResult proposed = Merge({a, b}, /*review=*/true, &status, op);
  ASSERT_TRUE(status.ok()) << status.error_message();
  pb::MergeRecord r;
  ASSERT_TRUE(Get(proposed.merge_id(), &r, reader).ok());
  EXPECT_EQ(r.requested_by(), "alice");
  EXPECT_EQ(List(pb::MERGE_STATE_UNSPECIFIED, reader).size(), 1u);
  EXPECT_EQ(List(pb::MERGE_STATE_UNSPECIFIED, robot).size(), 1u);

  for (const std::string& who : {reader, robot}) {
    const grpc::Status denied = Approve(proposed.merge_id(), nullptr, who);
    EXPECT_EQ(denied.error_code(), grpc::StatusCode::PERMISSION_DENIED);
    EXPECT_THAT(denied.error_message(), HasSubstr("merge"));
    EXPECT_EQ(Reject(proposed.merge_id(), "no", nullptr, who).error_code(),
              grpc::StatusCode::PERMISSION_DENIED);
  }
  EXPECT_EQ(Approve(proposed.merge_id(), nullptr, "").error_code(),
            grpc::StatusCode::UNAUTHENTICATED);
  ASSERT_TRUE(Get(proposed.merge_id(), &r, reader).ok());
  EXPECT_EQ(r.state(), pb::MERGE_STATE_PROPOSED);

  ASSERT_TRUE(Approve(proposed.merge_id(), &r, op).ok());
  EXPECT_EQ(r.decided_by(), "alice");
  EXPECT_EQ(Approve(proposed.merge_id(), nullptr, admin).error_code(),
            grpc::StatusCode::FAILED_PRECONDITION);

  // Audited: the proposal, the approval, the refused second approval, the denials.
  const std::vector<pb::AuditEntry> audit = Audit(admin);
  auto find = [&](const std::string& action, const std::string& who, const std::string& result) {
    for (const pb::AuditEntry& e : audit) {
      if (e.action() == action && e.who() == who && e.result().rfind(result, 0) == 0) return true;
    }
    return false;
  };
  EXPECT_TRUE(find("MergeSubmaps", "alice", "proposed"));
  EXPECT_TRUE(find("ApproveMerge", "alice", "ok"));
  EXPECT_TRUE(find("ApproveMerge", "root", "FAILED_PRECONDITION"));
  EXPECT_TRUE(find("ApproveMerge", "dash", "denied"));
  EXPECT_TRUE(find("RejectMerge", "r1-key", "denied"));
}

}  // namespace
}  // namespace mapd::testing
