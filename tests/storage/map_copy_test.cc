// Copying a map between stores (storage/map_copy.h), on every pair of
// backends: the copy reads back as the source does, ids of observations and
// ties included, and a copy that cannot be faithful is refused.
#include "storage/map_copy.h"

#include <gtest/gtest.h>

#include <memory>
#include <string>
#include <tuple>

#include "common/postgres.h"
#include "common/temp_dir.h"
#include "storage/postgres/store.h"
#include "storage/sqlite/store.h"

namespace mapd::storage {
namespace {

using Backends = std::tuple<std::string, std::string>;  // source, target

class MapCopyTest : public ::testing::TestWithParam<Backends> {
 protected:
  void SetUp() override {
    const auto [from, to] = GetParam();
    if (from == "postgresql" || to == "postgresql") {
      mapd::testing::PostgresCluster* cluster = mapd::testing::PostgresCluster::Shared();
      if (cluster == nullptr) GTEST_SKIP() << "no PostgreSQL (install postgresql-15)";
      conninfo_ = cluster->NewDatabase();
    }
    from_ = Open(from, "site-a");
    to_ = Open(to, "site-b");
    ASSERT_TRUE(from_ && to_);
  }

  std::unique_ptr<Store> Open(const std::string& backend, const std::string& map) {
    if (backend == "postgresql") {
      auto s = PgStore::Open(conninfo_, map, StoreOptions{});
      EXPECT_TRUE(s.ok()) << s.status().ToString();
      return s.ok() ? std::move(s).value() : nullptr;
    }
    auto s = SqliteStore::Open(dir_.File(map + ".db"), StoreOptions{});
    EXPECT_TRUE(s.ok()) << s.status().ToString();
    return s.ok() ? std::move(s).value() : nullptr;
  }

  template <typename Fn>
  void Write(Store& store, Fn fn) {
    auto txn = store.BeginWrite();
    ASSERT_TRUE(txn.ok()) << txn.status().ToString();
    Status s = fn(txn->get());
    ASSERT_TRUE(s.ok()) << s.ToString();
    ASSERT_TRUE((*txn)->Commit().ok());
  }

  void Observe(const std::string& robot, const std::string& session, uint64_t seq, FrameKind kind) {
    geometry::SensorObservation f;
    f.T_frame_sensor.translation = {static_cast<double>(seq), 0, 0};
    f.lines.push_back({{0, 0, 0}, {1.0 + static_cast<double>(seq), 0, 0}});
    NewObservation o;
    o.robot = robot;
    o.session = session;
    o.seq = seq;
    o.stamp_ns = 100 + static_cast<int64_t>(seq);
    o.received_ns = 900 + static_cast<int64_t>(seq);
    o.frame_kind = kind;
    o.features = &f;
    Write(*from_, [&](WriteTransaction* t) { return t->InsertObservation(o).status(); });
  }

  NewSubmap Submap(const std::string& robot, const std::string& name, const std::string& data,
                   const std::string& session) {
    NewSubmap m;
    m.meta.robot = robot;
    m.meta.name = name;
    m.meta.resolution_m = 0.1;
    m.meta.occupied_voxels = 12;
    m.meta.created_ns = 777;
    m.session = session;
    m.data = data;
    return m;
  }

  // A source with what a year of a site holds: two robots, a session in its
  // own frame tied by an accepted merge, submaps, merges of every state,
  // placements, the global map, fused rows, audit rows and tokens.
  void FillSource() {
    Observe("r1", "s1", 1, FrameKind::kMap);
    Observe("r2", "local", 1, FrameKind::kLocal);
    Observe("r1", "s1", 2, FrameKind::kMap);
    Observe("r2", "local", 2, FrameKind::kLocal);
    int64_t a = 0, b = 0, gone = 0;
    const std::string bytes_a(3000, 'a'), bytes_b(2000, 'b'), merged_bytes(4000, 'm');
    Write(*from_, [&](WriteTransaction* t) {
      a = *t->InsertSubmap(Submap("r1", "room", bytes_a, "s1"));
      room_id_ = a;
      b = *t->InsertSubmap(Submap("r2", "room", bytes_b, "local"));
      gone = *t->InsertSubmap(Submap("r2", "old", "x", ""));
      return Status::Ok();
    });
    // A refused merge of a submap deleted since, then an accepted one that
    // ties r2's session, then a rejected proposal.
    NewMerge refused;
    refused.record.state = MergeState::kRefused;
    refused.record.reason = "too few corners";
    refused.record.inputs.resize(2);
    refused.record.inputs[0].submap_id = a;
    refused.record.inputs[1].submap_id = gone;
    NewMerge accepted;
    accepted.record.state = MergeState::kAccepted;
    accepted.record.requested_by = "op";
    accepted.record.decided_by = "op";
    accepted.record.decided_ns = 55;
    accepted.record.inputs.resize(2);
    accepted.record.inputs[0].submap_id = a;
    accepted.record.inputs[1].submap_id = b;
    accepted.record.inputs[1].aligned = true;
    accepted.record.inputs[1].matched_corners = 9;
    accepted.record.inputs[1].T_reference_submap.translation = {1, 2, 0};
    accepted.merged = Submap("", "", merged_bytes, "");
    geometry::Rigid3 T_map_local;
    T_map_local.translation = {1, 2, 0};
    Write(*from_, [&](WriteTransaction* t) {
      MAPD_RETURN_IF_ERROR(t->RecordMerge(refused).status());
      MAPD_RETURN_IF_ERROR(t->DeleteSubmap(gone));
      return Status::Ok();
    });
    Write(*from_, [&](WriteTransaction* t) {
      t->set_tie_point(4);
      StatusOr<MergeIds> ids = t->RecordMerge(accepted);
      if (!ids.ok()) return ids.status();
      merged_id_ = ids->merged_submap_id;
      MAPD_RETURN_IF_ERROR(
          t->TieSession(from_->FindSession("r2", "local")->session_id, T_map_local));
      MAPD_RETURN_IF_ERROR(t->PlaceSubmap(a, ids->merge_id, geometry::Rigid3()));
      MAPD_RETURN_IF_ERROR(t->PlaceSubmap(b, ids->merge_id, T_map_local));
      GlobalMapRecord g;
      g.version = 3;
      g.resolution_m = 0.1;
      g.members = {{a, geometry::Rigid3()}, {b, T_map_local}};
      g.data = "global bytes";
      return t->PutGlobalMap(g);
    });
    NewMerge proposed = accepted;
    proposed.record.state = MergeState::kProposed;
    proposed.record.decided_by.clear();
    proposed.record.decided_ns = 0;
    Write(*from_, [&](WriteTransaction* t) {
      StatusOr<MergeIds> ids = t->RecordMerge(proposed);
      if (!ids.ok()) return ids.status();
      return t->DecideMerge(ids->merge_id, MergeState::kRejected, "op2", 66, "looks wrong");
    });
    Observe("r2", "local", 3, FrameKind::kLocal);
    Write(*from_, [&](WriteTransaction* t) {
      FusedRow row;
      row.id = 41;
      row.segment = {{0, 0}, {3, 0}};
      row.support = 4;
      row.robots = "r1,r2";
      MAPD_RETURN_IF_ERROR(t->UpsertFused(row));
      FusedPlaneRow plane;
      plane.id = 5;
      plane.boundary = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}};
      MAPD_RETURN_IF_ERROR(t->UpsertFusedPlane(plane));
      AuditEntry e;
      e.time_ns = 10;
      e.who = "op";
      e.action = "MergeSubmaps";
      e.result = "ok";
      MAPD_RETURN_IF_ERROR(t->AppendAudit(e));
      e.time_ns = 11;
      e.action = "DecideMerge";
      MAPD_RETURN_IF_ERROR(t->AppendAudit(e));
      TokenRecord token;
      token.name = "robot-r1";
      token.role = "robot";
      token.robot_id = "r1";
      token.secret_sha256 = std::string(32, 's');
      token.created_ns = 5;
      MAPD_RETURN_IF_ERROR(t->InsertToken(token).status());
      token.name = "old-admin";
      token.role = "admin";
      token.robot_id.clear();
      StatusOr<int64_t> old = t->InsertToken(token);
      if (!old.ok()) return old.status();
      return t->RevokeToken(*old, 8);
    });
  }

  std::string conninfo_;
  mapd::testing::TempDir dir_;
  std::unique_ptr<Store> from_, to_;
  int64_t room_id_ = 0;    // r1's submap, in the source
  int64_t merged_id_ = 0;  // the accepted merge's map, in the source
};

TEST_P(MapCopyTest, TheCopyReadsBackAsTheSource) {
  FillSource();
  MapCopyOptions options;
  options.observations_per_commit = 2;  // ties fall between and inside groups
  options.copy_tokens = true;
  options.scope_tokens_to = "site-b";
  int commits = 0;
  options.after_commit = [&](const MapCopyReport&) {
    ++commits;
    return Status::Ok();
  };
  StatusOr<MapCopyReport> report = CopyMap(*from_, *to_, options);
  ASSERT_TRUE(report.ok()) << report.status().ToString();
  EXPECT_EQ(report->observations, 5u);
  EXPECT_EQ(report->ties, 1u);
  EXPECT_EQ(report->robots, 2u);
  EXPECT_EQ(report->sessions, 2u);
  EXPECT_EQ(report->merges, 3u);
  EXPECT_EQ(report->submaps, 4u);  // two uploads and two merged maps
  EXPECT_EQ(report->placements, 2u);
  EXPECT_TRUE(report->global_map);
  EXPECT_EQ(report->audit_rows, 2u);
  EXPECT_EQ(report->tokens, 2u);
  EXPECT_EQ(report->unknown_merge_inputs, 1u);
  EXPECT_GT(commits, 6);

  // Observations: same ids, stamps, features.
  std::vector<StoredObservation> a, b;
  ASSERT_TRUE(from_
                  ->ForEachObservation([&](const StoredObservation& o) {
                    a.push_back(o);
                    return Status::Ok();
                  })
                  .ok());
  ASSERT_TRUE(to_->ForEachObservation([&](const StoredObservation& o) {
                   b.push_back(o);
                   return Status::Ok();
                 })
                  .ok());
  ASSERT_EQ(a.size(), b.size());
  for (size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(b[i].id, a[i].id);
    EXPECT_EQ(to_->RobotName(b[i].robot_id), from_->RobotName(a[i].robot_id));
    EXPECT_EQ(b[i].seq, a[i].seq);
    EXPECT_EQ(b[i].stamp_ns, a[i].stamp_ns);
    EXPECT_EQ(b[i].received_ns, a[i].received_ns);
    ASSERT_EQ(b[i].features.lines.size(), 1u);
    EXPECT_EQ(b[i].features.lines[0].b, a[i].features.lines[0].b);
  }
  // The tie: same place in the commit order, same transform.
  StatusOr<SessionFrame> local = to_->FindSession("r2", "local");
  ASSERT_TRUE(local.ok());
  EXPECT_TRUE(local->tied);
  EXPECT_EQ(local->tied_through_observation, 4);
  EXPECT_EQ(local->tie_seq, 1);
  EXPECT_EQ(local->T_map_frame.translation, Eigen::Vector3d(1, 2, 0));
  // Merges with their states, deciders and renumbered inputs.
  StatusOr<std::vector<MergeRecord>> merges = to_->ListMerges();
  ASSERT_TRUE(merges.ok());
  ASSERT_EQ(merges->size(), 3u);
  EXPECT_EQ((*merges)[0].state, MergeState::kRefused);
  EXPECT_EQ((*merges)[0].inputs[1].submap_id, 0);
  EXPECT_EQ((*merges)[1].state, MergeState::kAccepted);
  EXPECT_EQ((*merges)[1].decided_by, "op");
  EXPECT_EQ((*merges)[1].inputs[1].matched_corners, 9);
  EXPECT_EQ((*merges)[2].state, MergeState::kRejected);
  EXPECT_EQ((*merges)[2].decided_by, "op2");
  EXPECT_EQ((*merges)[2].decided_ns, 66);
  EXPECT_EQ((*merges)[2].reason, "looks wrong");
  const int64_t new_a = report->submap_ids.at(room_id_);
  EXPECT_EQ((*merges)[1].inputs[0].submap_id, new_a);
  EXPECT_EQ(*to_->GetSubmapData(new_a), std::string(3000, 'a'));
  EXPECT_EQ(to_->GetSubmap(new_a)->robot, "r1");
  EXPECT_EQ(to_->GetSubmap(new_a)->session_id, to_->FindSession("r1", "s1")->session_id);
  EXPECT_EQ(*to_->GetSubmapData(report->submap_ids.at(merged_id_)), std::string(4000, 'm'));
  EXPECT_EQ(to_->ListSubmaps(kMergedRobot)->size(), 2u);
  // Placements and the global map name the target's ids.
  StatusOr<std::vector<SubmapPlacement>> placed = to_->ListPlacements();
  ASSERT_TRUE(placed.ok());
  ASSERT_EQ(placed->size(), 2u);
  EXPECT_EQ((*placed)[0].submap_id, new_a);
  EXPECT_EQ((*placed)[0].merge_id, (*merges)[1].id);
  StatusOr<GlobalMapRecord> global = to_->GetGlobalMap(true);
  ASSERT_TRUE(global.ok());
  EXPECT_EQ(global->version, 3u);
  EXPECT_EQ(global->data, "global bytes");
  EXPECT_EQ(global->members[0].submap_id, new_a);
  // The fused map, the audit log (oldest first as written), tokens scoped.
  EXPECT_EQ(to_->LoadFused()->at(0).robots, "r1,r2");
  EXPECT_EQ(to_->LoadFusedPlanes()->at(0).boundary.size(), 3u);
  StatusOr<std::vector<AuditEntry>> audit = to_->ListAudit(10);
  ASSERT_EQ(audit->size(), 2u);
  EXPECT_EQ((*audit)[0].action, "DecideMerge");
  StatusOr<std::vector<TokenRecord>> tokens = to_->ListTokens();
  ASSERT_EQ(tokens->size(), 2u);
  EXPECT_EQ((*tokens)[0].maps, "site-b");
  EXPECT_EQ((*tokens)[0].secret_sha256, std::string(32, 's'));
  EXPECT_EQ((*tokens)[1].revoked_ns, 8);
}

TEST_P(MapCopyTest, ATargetWithDataIsRefusedAndKeptAsItWas) {
  FillSource();
  Write(*to_, [&](WriteTransaction* t) {
    geometry::SensorObservation f;
    NewObservation o;
    o.robot = "other";
    o.session = "s";
    o.seq = 1;
    o.features = &f;
    return t->InsertObservation(o).status();
  });
  StatusOr<MapCopyReport> report = CopyMap(*from_, *to_);
  ASSERT_FALSE(report.ok());
  EXPECT_EQ(report.status().code(), StatusCode::kFailedPrecondition);
  EXPECT_NE(report.status().message().find("holds data already"), std::string::npos)
      << report.status().ToString();
  EXPECT_EQ(*to_->NewestObservationId(), 1);
}

TEST_P(MapCopyTest, ATakenTokenNameIsRefusedBeforeAnythingIsWritten) {
  FillSource();
  Write(*to_, [&](WriteTransaction* t) {
    TokenRecord token;
    token.name = "robot-r1";
    token.role = "reader";
    token.secret_sha256 = std::string(32, 't');
    return t->InsertToken(token).status();
  });
  MapCopyOptions options;
  options.copy_tokens = true;
  StatusOr<MapCopyReport> report = CopyMap(*from_, *to_, options);
  ASSERT_FALSE(report.ok());
  EXPECT_EQ(report.status().code(), StatusCode::kAlreadyExists);
  EXPECT_NE(report.status().message().find("robot-r1"), std::string::npos);
  EXPECT_EQ(*to_->NewestObservationId(), 0);
}

TEST_P(MapCopyTest, AMapThinnedByRawRetentionIsRefused) {
  Observe("r1", "s1", 1, FrameKind::kMap);
  Observe("r1", "s1", 2, FrameKind::kMap);
  Observe("r1", "s1", 3, FrameKind::kMap);
  Write(*from_, [&](WriteTransaction* t) {
    FusionSnapshot snapshot;
    snapshot.through_observation = 3;
    snapshot.state = "state";
    snapshot.has_plane_state = true;
    MAPD_RETURN_IF_ERROR(t->InsertSnapshot(snapshot, 2));
    return t->DropRawObservations(/*received_before_ns=*/1'000'000, 10).status();
  });
  StatusOr<MapCopyReport> report = CopyMap(*from_, *to_);
  ASSERT_FALSE(report.ok());
  EXPECT_EQ(report.status().code(), StatusCode::kFailedPrecondition);
  EXPECT_NE(report.status().message().find("raw retention"), std::string::npos)
      << report.status().ToString();
}

INSTANTIATE_TEST_SUITE_P(Pairs, MapCopyTest,
                         ::testing::Values(Backends{"sqlite", "postgresql"},
                                           Backends{"postgresql", "sqlite"},
                                           Backends{"sqlite", "sqlite"}),
                         [](const ::testing::TestParamInfo<Backends>& p) {
                           return std::get<0>(p.param) + "_to_" + std::get<1>(p.param);
                         });

}  // namespace
}  // namespace mapd::storage
