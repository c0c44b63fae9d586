// Submaps, merges and session ties in the store (storage/store.h).
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "storage/store.h"
#include "storage/support/store_fixture.h"

namespace mapd::storage {
namespace {

// SQL that turns schema 8's merge_inputs back into schema 7's.
constexpr const char* kDropGateFigures =
    "ALTER TABLE merge_inputs DROP COLUMN source; "
    "ALTER TABLE merge_inputs DROP COLUMN support_fraction; "
    "ALTER TABLE merge_inputs DROP COLUMN shared_free_ratio; "
    "ALTER TABLE merge_inputs DROP COLUMN restart_spread_voxels; "
    "ALTER TABLE merge_inputs DROP COLUMN second_residual_m; ";

class SubmapStoreTest : public testing::StoreFixture {
 protected:
  NewSubmap Submap(const std::string& robot, const std::string& name, const std::string& data,
                   const std::string& session = "") {
    NewSubmap m;
    m.meta.robot = robot;
    m.meta.name = name;
    m.meta.format = SubmapFormat::kOctomapBt;
    m.meta.resolution_m = 0.1;
    m.meta.occupied_voxels = 12;
    m.meta.free_voxels = 34;
    m.meta.bounds_min = {-1, -2, -3};
    m.meta.bounds_max = {4, 5, 6};
    m.meta.created_ns = 777;
    m.session = session;
    m.data = data;
    return m;
  }

  StatusOr<int64_t> Insert(const NewSubmap& m) {
    int64_t id = 0;
    Status s = Write([&](WriteTransaction* t) {
      StatusOr<int64_t> r = t->InsertSubmap(m);
      if (!r.ok()) return r.status();
      id = *r;
      return Status::Ok();
    });
    if (!s.ok()) return s;
    return id;
  }

  // One observation in a local-frame session, so that the session exists.
  void OpenLocalSession(const std::string& robot, const std::string& session) {
    NewObservation o;
    o.robot = robot;
    o.session = session;
    o.seq = 1;
    o.frame_kind = FrameKind::kLocal;
    o.features = &features_;
    ASSERT_TRUE(Write([&](WriteTransaction* t) { return t->InsertObservation(o).status(); }).ok());
  }

  StatusOr<MergeIds> Record(const NewMerge& merge) {
    MergeIds ids;
    Status s = Write([&](WriteTransaction* t) {
      StatusOr<MergeIds> r = t->RecordMerge(merge);
      if (!r.ok()) return r.status();
      ids = *r;
      return Status::Ok();
    });
    if (!s.ok()) return s;
    return ids;
  }

  NewMerge Accepted(int64_t a, int64_t b, const std::string& merged_bytes) {
    NewMerge m;
    m.record.state = MergeState::kAccepted;
    m.record.created_ns = 99;
    MergeInputRecord ia;
    ia.submap_id = a;
    ia.aligned = true;
    MergeInputRecord ib;
    ib.submap_id = b;
    ib.aligned = true;
    ib.T_reference_submap.translation = {1.5, -2, 0.25};
    ib.T_reference_submap.rotation =
        Eigen::Quaterniond(Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitZ()));
    ib.matched_corners = 9;
    ib.residual_m = 0.04;
    ib.overlap_score = 0.8;
    ib.matched = {{{0.5, 1, 2}, {1.25, -0.5, 2.25}}, {{-3, 4.5, 0.125}, {-7, 8, 0.375}}};
    ib.source = "correlation yaw 12.0 deg";
    ib.support_fraction = 0.5;
    ib.shared_free_ratio = 7.25;
    ib.restart_spread_voxels = -1;  // not measured
    ib.second_residual_m = 0.09;
    m.record.inputs = {ia, ib};
    m.merged = Submap("", "", merged_bytes);
    return m;
  }

  static MergeInputRecord Input(int64_t submap_id) {
    MergeInputRecord i;
    i.submap_id = submap_id;
    return i;
  }

  geometry::SensorObservation features_ = [] {
    geometry::SensorObservation f;
    f.lines.push_back({{0, 0, 0}, {3, 0, 0}});
    return f;
  }();
};

using SubmapStoreConformanceTest = testing::OnEveryBackend<SubmapStoreTest>;

TEST_P(SubmapStoreConformanceTest, StoresListsAndReadsBackBytesAndMetadata) {
  std::string bytes = "# Octomap OcTree binary file\n";
  bytes += std::string("\0\x01\xff\x80", 4);  // binary, with a NUL
  auto id = Insert(Submap("r1", "hall", bytes));
  ASSERT_TRUE(id.ok()) << id.status().ToString();
  ASSERT_TRUE(Insert(Submap("r2", "hall", "x")).ok());  // same name, other robot

  auto meta = store_->GetSubmap(*id);
  ASSERT_TRUE(meta.ok()) << meta.status().ToString();
  EXPECT_EQ(meta->robot, "r1");
  EXPECT_EQ(meta->name, "hall");
  EXPECT_EQ(meta->format, SubmapFormat::kOctomapBt);
  EXPECT_EQ(meta->resolution_m, 0.1);
  EXPECT_EQ(meta->occupied_voxels, 12u);
  EXPECT_EQ(meta->free_voxels, 34u);
  EXPECT_EQ(meta->bounds_min, Eigen::Vector3d(-1, -2, -3));
  EXPECT_EQ(meta->bounds_max, Eigen::Vector3d(4, 5, 6));
  EXPECT_EQ(meta->size_bytes, bytes.size());
  EXPECT_EQ(meta->session_id, 0);
  auto data = store_->GetSubmapData(*id);
  ASSERT_TRUE(data.ok());
  EXPECT_EQ(*data, bytes);

  auto all = store_->ListSubmaps("");
  ASSERT_TRUE(all.ok());
  EXPECT_EQ(all->size(), 2u);
  auto r2 = store_->ListSubmaps("r2");
  ASSERT_TRUE(r2.ok());
  ASSERT_EQ(r2->size(), 1u);
  EXPECT_EQ((*r2)[0].robot, "r2");
  EXPECT_TRUE(store_->ListSubmaps("nobody")->empty());
  EXPECT_EQ(store_->Counts()->submaps, 2u);

  Reopen();  // survives a restart
  EXPECT_EQ(*store_->GetSubmapData(*id), bytes);
}

TEST_P(SubmapStoreConformanceTest, NameIsUniquePerRobot) {
  ASSERT_TRUE(Insert(Submap("r1", "hall", "a")).ok());
  auto again = Insert(Submap("r1", "hall", "b"));
  EXPECT_EQ(again.status().code(), StatusCode::kAlreadyExists);
  EXPECT_NE(again.status().message().find("hall"), std::string::npos);
  EXPECT_EQ(*store_->GetSubmapData(store_->ListSubmaps("r1")->at(0).id), "a");
}

TEST_P(SubmapStoreConformanceTest, UnknownSessionIsRefusedKnownOneIsLinked) {
  auto unknown = Insert(Submap("r1", "hall", "a", "s1"));
  EXPECT_EQ(unknown.status().code(), StatusCode::kFailedPrecondition);
  EXPECT_TRUE(store_->ListSubmaps("")->empty());

  OpenLocalSession("r1", "s1");
  auto id = Insert(Submap("r1", "hall", "a", "s1"));
  ASSERT_TRUE(id.ok()) << id.status().ToString();
  auto session = store_->FindSession("r1", "s1");
  ASSERT_TRUE(session.ok());
  EXPECT_EQ(store_->GetSubmap(*id)->session_id, session->session_id);
}

TEST_P(SubmapStoreConformanceTest, DeleteRemovesAndReportsNotFound) {
  auto id = Insert(Submap("r1", "hall", "a"));
  ASSERT_TRUE(id.ok());
  ASSERT_TRUE(Write([&](WriteTransaction* t) { return t->DeleteSubmap(*id); }).ok());
  EXPECT_EQ(store_->GetSubmap(*id).status().code(), StatusCode::kNotFound);
  EXPECT_EQ(store_->GetSubmapData(*id).status().code(), StatusCode::kNotFound);
  EXPECT_EQ(Write([&](WriteTransaction* t) { return t->DeleteSubmap(*id); }).code(),
            StatusCode::kNotFound);
  // The name is free again.
  EXPECT_TRUE(Insert(Submap("r1", "hall", "b")).ok());
}

TEST_P(SubmapStoreConformanceTest, AcceptedMergeStoresRecordAndMergedMapAndPinsItsSubmaps) {
  const int64_t a = *Insert(Submap("r1", "a", "A"));
  const int64_t b = *Insert(Submap("r2", "b", "B"));
  auto ids = Record(Accepted(a, b, "MERGED"));
  ASSERT_TRUE(ids.ok()) << ids.status().ToString();
  EXPECT_GT(ids->merge_id, 0);
  EXPECT_GT(ids->merged_submap_id, 0);

  auto merged = store_->GetSubmap(ids->merged_submap_id);
  ASSERT_TRUE(merged.ok()) << merged.status().ToString();
  EXPECT_EQ(merged->robot, kMergedRobot);
  EXPECT_EQ(merged->name, "merge-" + std::to_string(ids->merge_id));
  EXPECT_EQ(*store_->GetSubmapData(merged->id), "MERGED");

  Reopen();
  auto record = store_->GetMerge(ids->merge_id);
  ASSERT_TRUE(record.ok()) << record.status().ToString();
  EXPECT_EQ(record->state, MergeState::kAccepted);
  EXPECT_EQ(record->merged_submap_id, ids->merged_submap_id);
  ASSERT_EQ(record->inputs.size(), 2u);
  EXPECT_EQ(record->inputs[1].submap_id, b);
  EXPECT_TRUE(record->inputs[1].aligned);
  EXPECT_EQ(record->inputs[1].matched_corners, 9);
  EXPECT_DOUBLE_EQ(record->inputs[1].overlap_score, 0.8);
  EXPECT_EQ(record->inputs[1].source, "correlation yaw 12.0 deg");
  EXPECT_EQ(record->inputs[1].support_fraction, 0.5);
  EXPECT_EQ(record->inputs[1].shared_free_ratio, 7.25);
  EXPECT_EQ(record->inputs[1].restart_spread_voxels, -1);
  EXPECT_EQ(record->inputs[1].second_residual_m, 0.09);
  EXPECT_TRUE(record->inputs[0].matched.empty());
  ASSERT_EQ(record->inputs[1].matched.size(), 2u);
  EXPECT_EQ(record->inputs[1].matched[0].in_submap, Eigen::Vector3d(0.5, 1, 2));
  EXPECT_EQ(record->inputs[1].matched[0].in_reference, Eigen::Vector3d(1.25, -0.5, 2.25));
  EXPECT_EQ(record->inputs[1].matched[1].in_submap, Eigen::Vector3d(-3, 4.5, 0.125));
  EXPECT_EQ(record->inputs[1].matched[1].in_reference, Eigen::Vector3d(-7, 8, 0.375));
  EXPECT_NEAR(record->inputs[1].T_reference_submap.translation.x(), 1.5, 1e-12);
  EXPECT_NEAR(record->inputs[1].T_reference_submap.rotation.angularDistance(
                  Eigen::Quaterniond(Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitZ()))),
              0.0, 1e-12);

  // The merged-map robot is not a robot of ListRobots / Counts.
  const std::vector<RobotSummary> robots = store_->ListRobots().value();
  for (const RobotSummary& r : robots) EXPECT_NE(r.name, kMergedRobot);
  EXPECT_EQ(store_->Counts()->robots, 2u);

  // Inputs and result of an accepted merge are pinned.
  for (int64_t id : {a, b, ids->merged_submap_id}) {
    const Status s = Write([&](WriteTransaction* t) { return t->DeleteSubmap(id); });
    EXPECT_EQ(s.code(), StatusCode::kFailedPrecondition) << id;
    EXPECT_NE(s.message().find("accepted merge"), std::string::npos);
    EXPECT_TRUE(store_->GetSubmap(id).ok());
  }
}

TEST_P(SubmapStoreConformanceTest, RefusedMergeIsRecordedWithoutMergedMapAndPinsNothing) {
  const int64_t a = *Insert(Submap("r1", "a", "A"));
  const int64_t b = *Insert(Submap("r2", "b", "B"));
  NewMerge m;
  m.record.state = MergeState::kRefused;
  m.record.reason = "FAILED_PRECONDITION: no corners in submap 2";
  m.record.inputs = {Input(a), Input(b)};
  auto ids = Record(m);
  ASSERT_TRUE(ids.ok()) << ids.status().ToString();
  EXPECT_EQ(ids->merged_submap_id, 0);
  EXPECT_EQ(store_->ListSubmaps("")->size(), 2u);
  auto record = store_->GetMerge(ids->merge_id);
  ASSERT_TRUE(record.ok());
  EXPECT_EQ(record->state, MergeState::kRefused);
  EXPECT_EQ(record->reason, m.record.reason);
  ASSERT_EQ(record->inputs.size(), 2u);
  EXPECT_FALSE(record->inputs[0].aligned);
  EXPECT_TRUE(Write([&](WriteTransaction* t) { return t->DeleteSubmap(a); }).ok());
}

// A placement stays as first recorded (as a session tie), and the global
// map's row comes back exactly: its members' poses bit for bit, so that the
// builder can tell a moved member from a kept one.
TEST_P(SubmapStoreConformanceTest, PlacementsKeepTheFirstAndTheGlobalMapComesBackExactly) {
  const int64_t a = *Insert(Submap("r1", "a", "A"));
  const int64_t b = *Insert(Submap("r2", "b", "B"));
  geometry::Rigid3 T;
  T.rotation = Eigen::Quaterniond(Eigen::AngleAxisd(0.1, Eigen::Vector3d(1, 2, 3).normalized()));
  T.translation = {0.1, -1.0 / 3.0, 1e-17};
  ASSERT_TRUE(Write([&](WriteTransaction* t) {
                MAPD_RETURN_IF_ERROR(t->PlaceSubmap(b, 4, T));
                return t->PlaceSubmap(b, 5, geometry::Rigid3::Identity());  // ignored
              }).ok());
  auto placements = store_->ListPlacements();
  ASSERT_TRUE(placements.ok()) << placements.status().ToString();
  ASSERT_EQ(placements->size(), 1u);
  EXPECT_EQ((*placements)[0].submap_id, b);
  EXPECT_EQ((*placements)[0].merge_id, 4);
  EXPECT_EQ((*placements)[0].T_map_submap.translation, T.translation);

  const Status none = store_->GetGlobalMap(true).status();
  EXPECT_EQ(none.code(), StatusCode::kNotFound);
  EXPECT_NE(none.message().find("no global map yet"), std::string::npos) << none.ToString();
  GlobalMapRecord map;
  map.version = 3;
  map.built_ns = 77;
  map.resolution_m = 0.05;
  map.occupied_voxels = 12;
  map.free_voxels = 34;
  map.members = {{a, geometry::Rigid3::Identity()}, {b, T}};
  map.data = std::string("BT\0bytes", 8);
  ASSERT_TRUE(Write([&](WriteTransaction* t) { return t->PutGlobalMap(map); }).ok());
  Reopen();
  auto read = store_->GetGlobalMap(/*with_data=*/true);
  ASSERT_TRUE(read.ok()) << read.status().ToString();
  EXPECT_EQ(read->version, 3u);
  EXPECT_EQ(read->built_ns, 77);
  EXPECT_EQ(read->resolution_m, 0.05);
  EXPECT_EQ(read->occupied_voxels, 12u);
  EXPECT_EQ(read->free_voxels, 34u);
  EXPECT_EQ(read->data, map.data);
  ASSERT_EQ(read->members.size(), 2u);
  EXPECT_EQ(read->members[0].submap_id, a);
  EXPECT_EQ(read->members[1].submap_id, b);
  EXPECT_EQ(read->members[1].T_map_submap.rotation.coeffs(), T.rotation.coeffs());
  EXPECT_EQ(read->members[1].T_map_submap.translation, T.translation);
  EXPECT_EQ(store_->GetGlobalMap(/*with_data=*/false)->data, "");

  map.version = 4;
  map.members.pop_back();
  ASSERT_TRUE(Write([&](WriteTransaction* t) { return t->PutGlobalMap(map); }).ok());
  EXPECT_EQ(store_->GetGlobalMap(false)->version, 4u);
  EXPECT_EQ(store_->GetGlobalMap(false)->members.size(), 1u);
  ASSERT_TRUE(Write([&](WriteTransaction* t) { return t->DeleteGlobalMap(); }).ok());
  EXPECT_EQ(store_->GetGlobalMap(false).status().code(), StatusCode::kNotFound);
}

TEST_P(SubmapStoreConformanceTest, ProposedMergeKeepsItsMapButIsNotInEffectUntilApproved) {
  const int64_t a = *Insert(Submap("r1", "a", "A"));
  const int64_t b = *Insert(Submap("r2", "b", "B"));
  const std::string merged_bytes = "PROPOSED";  // NewSubmap::data views it
  NewMerge proposal = Accepted(a, b, merged_bytes);
  proposal.record.state = MergeState::kProposed;
  proposal.record.requested_by = "ops";
  auto ids = Record(proposal);
  ASSERT_TRUE(ids.ok()) << ids.status().ToString();
  EXPECT_GT(ids->merged_submap_id, 0);
  EXPECT_EQ(*store_->GetSubmapData(ids->merged_submap_id), "PROPOSED");
  auto record = store_->GetMerge(ids->merge_id);
  ASSERT_TRUE(record.ok());
  EXPECT_EQ(record->state, MergeState::kProposed);
  EXPECT_EQ(record->requested_by, "ops");
  EXPECT_EQ(record->decided_ns, 0);

  auto decide = [&](int64_t id, MergeState state) {
    return Write([&](WriteTransaction* t) { return t->DecideMerge(id, state, "boss", 500, ""); });
  };
  EXPECT_EQ(decide(ids->merge_id + 7, MergeState::kAccepted).code(), StatusCode::kNotFound);
  EXPECT_EQ(decide(ids->merge_id, MergeState::kRefused).code(), StatusCode::kInvalidArgument);
  ASSERT_TRUE(decide(ids->merge_id, MergeState::kAccepted).ok());
  Reopen();
  record = store_->GetMerge(ids->merge_id);
  EXPECT_EQ(record->state, MergeState::kAccepted);
  EXPECT_EQ(record->decided_by, "boss");
  EXPECT_EQ(record->decided_ns, 500);
  const Status again = decide(ids->merge_id, MergeState::kRejected);
  EXPECT_EQ(again.code(), StatusCode::kFailedPrecondition);
  EXPECT_NE(again.message().find("is accepted"), std::string::npos) << again.ToString();
  // Approved, it pins its inputs like any accepted merge.
  EXPECT_EQ(Write([&](WriteTransaction* t) { return t->DeleteSubmap(a); }).code(),
            StatusCode::kFailedPrecondition);
}

TEST_P(SubmapStoreConformanceTest, RejectedProposalPinsNothingAndKeepsTheReason) {
  const int64_t a = *Insert(Submap("r1", "a", "A"));
  const int64_t b = *Insert(Submap("r2", "b", "B"));
  const std::string merged_bytes = "P";  // NewSubmap::data views it
  NewMerge proposal = Accepted(a, b, merged_bytes);
  proposal.record.state = MergeState::kProposed;
  auto ids = Record(proposal);
  ASSERT_TRUE(ids.ok());
  ASSERT_TRUE(Write([&](WriteTransaction* t) {
                return t->DecideMerge(ids->merge_id, MergeState::kRejected, "boss", 9, "askew");
              }).ok());
  auto record = store_->GetMerge(ids->merge_id);
  EXPECT_EQ(record->state, MergeState::kRejected);
  EXPECT_EQ(record->reason, "askew");
  for (int64_t id : {a, ids->merged_submap_id})
    EXPECT_TRUE(Write([&](WriteTransaction* t) { return t->DeleteSubmap(id); }).ok()) << id;
}

// A database of schema 5 (before review): its merges read as accepted /
// refused.
TEST_F(SubmapStoreTest, MergesOfAnOlderDatabaseShowAsAcceptedOrRefused) {
  const int64_t a = *Insert(Submap("r1", "a", "A"));
  const int64_t b = *Insert(Submap("r2", "b", "B"));
  auto accepted = Record(Accepted(a, b, "OLD"));
  ASSERT_TRUE(accepted.ok());
  NewMerge refused;
  refused.record.reason = "no overlap";
  refused.record.inputs = {Input(a), Input(b)};
  ASSERT_TRUE(Record(refused).ok());
  DowngradeAndReopen(std::string(testing::kUndoSnapshotParts) +
                     "ALTER TABLE merges DROP COLUMN requested_by; "
                     "ALTER TABLE merges DROP COLUMN decided_by; "
                     "ALTER TABLE merges DROP COLUMN decided_ns; "
                     "ALTER TABLE merge_inputs DROP COLUMN matched_points; " +
                     std::string(kDropGateFigures) +
                     "DELETE FROM schema_version WHERE version >= 6");
  auto merges = store_->ListMerges();
  ASSERT_TRUE(merges.ok()) << merges.status().ToString();
  ASSERT_EQ(merges->size(), 2u);
  EXPECT_EQ((*merges)[0].state, MergeState::kAccepted);
  EXPECT_EQ((*merges)[0].decided_ns, (*merges)[0].created_ns);
  EXPECT_EQ((*merges)[0].requested_by, "");
  EXPECT_EQ((*merges)[1].state, MergeState::kRefused);
  EXPECT_EQ((*merges)[1].reason, "no overlap");
}

// Gate figures that are not numbers (NaN, infinite) are stored as not
// measured (-1), not as garbage, and the merge is recorded whole.
TEST_P(SubmapStoreConformanceTest, GateFiguresThatAreNotNumbersReadAsNotMeasured) {
  const int64_t a = *Insert(Submap("r1", "a", "A"));
  const int64_t b = *Insert(Submap("r2", "b", "B"));
  const std::string merged_bytes = "M";  // NewSubmap::data views it
  NewMerge m = Accepted(a, b, merged_bytes);
  m.record.inputs[1].support_fraction = std::nan("");
  m.record.inputs[1].second_residual_m = std::numeric_limits<double>::infinity();
  auto ids = Record(m);
  ASSERT_TRUE(ids.ok()) << ids.status().ToString();
  auto record = store_->GetMerge(ids->merge_id);
  ASSERT_TRUE(record.ok()) << record.status().ToString();
  EXPECT_EQ(record->inputs[1].support_fraction, -1);
  EXPECT_EQ(record->inputs[1].second_residual_m, -1);
  EXPECT_EQ(record->inputs[1].shared_free_ratio, 7.25);  // the others as given
  EXPECT_EQ(*store_->GetSubmapData(record->merged_submap_id), "M");
}

// A database of schema 7 (merges without the rest of their gate figures)
// opens, its merges read as not measured (-1, no source), and new merges
// store theirs.
TEST_F(SubmapStoreTest, MergesBeforeGateFiguresReadAsNotMeasured) {
  const int64_t a = *Insert(Submap("r1", "a", "A"));
  const int64_t b = *Insert(Submap("r2", "b", "B"));
  auto old_merge = Record(Accepted(a, b, "OLD"));
  ASSERT_TRUE(old_merge.ok());
  DowngradeAndReopen(std::string(testing::kUndoSnapshotParts) + kDropGateFigures +
                     "DELETE FROM schema_version WHERE version >= 8");
  auto old_record = store_->GetMerge(old_merge->merge_id);
  ASSERT_TRUE(old_record.ok()) << old_record.status().ToString();
  ASSERT_EQ(old_record->inputs.size(), 2u);
  EXPECT_EQ(old_record->inputs[1].matched_corners, 9);
  EXPECT_EQ(old_record->inputs[1].matched.size(), 2u);
  EXPECT_EQ(old_record->inputs[1].source, "");
  EXPECT_EQ(old_record->inputs[1].support_fraction, -1);
  EXPECT_EQ(old_record->inputs[1].shared_free_ratio, -1);
  EXPECT_EQ(old_record->inputs[1].second_residual_m, -1);

  auto new_merge = Record(Accepted(a, b, "NEW"));
  ASSERT_TRUE(new_merge.ok()) << new_merge.status().ToString();
  auto new_record = store_->GetMerge(new_merge->merge_id);
  ASSERT_TRUE(new_record.ok());
  EXPECT_EQ(new_record->inputs[1].shared_free_ratio, 7.25);
}

// A database of schema 6 (merges without their matched corner pairs) opens,
// its merges keep their evidence counts and read as no pairs, and new merges
// store their pairs.
TEST_F(SubmapStoreTest, MergesBeforeMatchedCornersOpenWithoutPairs) {
  const int64_t a = *Insert(Submap("r1", "a", "A"));
  const int64_t b = *Insert(Submap("r2", "b", "B"));
  auto old_merge = Record(Accepted(a, b, "OLD"));
  ASSERT_TRUE(old_merge.ok());
  DowngradeAndReopen(std::string(testing::kUndoSnapshotParts) +
                     "ALTER TABLE merge_inputs DROP COLUMN matched_points; " +
                     std::string(kDropGateFigures) +
                     "DELETE FROM schema_version WHERE version >= 7");
  auto old_record = store_->GetMerge(old_merge->merge_id);
  ASSERT_TRUE(old_record.ok()) << old_record.status().ToString();
  ASSERT_EQ(old_record->inputs.size(), 2u);
  EXPECT_EQ(old_record->inputs[1].matched_corners, 9);
  EXPECT_TRUE(old_record->inputs[1].matched.empty());
  EXPECT_EQ(*store_->GetSubmapData(old_record->merged_submap_id), "OLD");

  auto new_merge = Record(Accepted(a, b, "NEW"));
  ASSERT_TRUE(new_merge.ok()) << new_merge.status().ToString();
  auto new_record = store_->GetMerge(new_merge->merge_id);
  ASSERT_TRUE(new_record.ok());
  ASSERT_EQ(new_record->inputs[1].matched.size(), 2u);
  EXPECT_EQ(new_record->inputs[1].matched[1].in_reference, Eigen::Vector3d(-7, 8, 0.375));
}

// A matched_points blob that is not whole pairs is reported, not misread.
TEST_F(SubmapStoreTest, TruncatedMatchedCornersAreAnError) {
  const int64_t a = *Insert(Submap("r1", "a", "A"));
  const int64_t b = *Insert(Submap("r2", "b", "B"));
  auto ids = Record(Accepted(a, b, "M"));
  ASSERT_TRUE(ids.ok());
  store_.reset();
  {
    auto db = OpenDatabase(dir_.File("map.db"), false);
    ASSERT_TRUE(db.ok());
    ASSERT_TRUE(
        Exec(db->get(), "UPDATE merge_inputs SET matched_points = x'0102' WHERE submap_id = " +
                            std::to_string(b))
            .ok());
  }
  Reopen();
  auto record = store_->GetMerge(ids->merge_id);
  ASSERT_FALSE(record.ok());
  EXPECT_EQ(record.status().code(), StatusCode::kInternal);
  EXPECT_NE(record.status().message().find("matched_points"), std::string::npos);
}

TEST_P(SubmapStoreConformanceTest, TiedSessionFramePersistsAndIsNeverMoved) {
  OpenLocalSession("r2", "s1");
  auto before = store_->FindSession("r2", "s1");
  ASSERT_TRUE(before.ok());
  EXPECT_FALSE(before->tied);
  geometry::Rigid3 T;
  T.translation = {3, 4, 0};
  T.rotation = Eigen::Quaterniond(Eigen::AngleAxisd(0.5, Eigen::Vector3d::UnitZ()));
  ASSERT_TRUE(
      Write([&](WriteTransaction* t) { return t->TieSession(before->session_id, T); }).ok());
  EXPECT_TRUE(store_->GetSession(before->session_id)->tied);

  // Moving a tie is refused; an unknown session is NotFound.
  EXPECT_EQ(
      Write([&](WriteTransaction* t) { return t->TieSession(before->session_id, {}); }).code(),
      StatusCode::kFailedPrecondition);
  EXPECT_EQ(Write([&](WriteTransaction* t) { return t->TieSession(12345, {}); }).code(),
            StatusCode::kNotFound);

  Reopen();
  auto after = store_->FindSession("r2", "s1");
  ASSERT_TRUE(after.ok());
  EXPECT_TRUE(after->tied);
  EXPECT_NEAR((after->T_map_frame.translation - T.translation).norm(), 0.0, 1e-12);
  EXPECT_NEAR(after->T_map_frame.rotation.angularDistance(T.rotation), 0.0, 1e-12);
  auto robots = store_->ListRobots();
  ASSERT_EQ(robots->size(), 1u);
  EXPECT_TRUE((*robots)[0].all_sessions_tied);
}

TEST_P(SubmapStoreConformanceTest, RolledBackTieLeavesTheCacheAlone) {
  OpenLocalSession("r2", "s1");
  const int64_t session = store_->FindSession("r2", "s1")->session_id;
  {
    auto txn = store_->BeginWrite();
    ASSERT_TRUE(txn.ok());
    ASSERT_TRUE((*txn)->TieSession(session, {}).ok());
    // No commit: rolled back.
  }
  EXPECT_FALSE(store_->GetSession(session)->tied);
  Reopen();
  EXPECT_FALSE(store_->GetSession(session)->tied);
}

MAPD_ON_EVERY_BACKEND(SubmapStoreConformanceTest);

}  // namespace
}  // namespace mapd::storage
