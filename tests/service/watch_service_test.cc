// WatchFeatureMap end to end on a real MapServer: the live feed, resuming,
// resyncs, filters, bad requests, limits and shutdown. The states a real core
// reaches only by accident (a feature leaving the bbox, a queue overflow)
// are on a FakeCore at the end.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <map>
#include <memory>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include "fake_core.h"
#include "server_fixture.h"
#include "service/map_service.h"
#include "service/proto_convert.h"
#include "service/watch_hub.h"
#include "watch_client.h"

namespace mapd::testing {
namespace {

using ::testing::HasSubstr;
using ::testing::UnorderedElementsAreArray;

pb::WatchFeatureMapRequest Since(uint64_t version) {
  pb::WatchFeatureMapRequest r;
  r.set_since_map_version(version);
  return r;
}

class WatchTest : public ServerFixture {
 protected:
  void SetUp() override {
    config_.watch.history = 64;
    config_.watch.queue = 16;
    config_.watch.max_watchers = 3;
    ServerFixture::SetUp();
  }

  // One batch per stream, and a read after it: each its own fuser round, so
  // each its own change in the history.
  void OneByOne(const std::vector<pb::ObservationBatch>& batches) {
    for (const auto& b : batches) {
      ASSERT_EQ(Stream({b}).size(), 1u);
      MapVersion();
    }
  }

  uint64_t MapVersion() {
    grpc::ClientContext ctx;
    pb::FeatureMapRequest request;
    request.set_max_wait_ms(30000);
    auto reader = stub_->GetFeatureMap(&ctx, request);
    pb::FeatureMapPage page;
    uint64_t version = 0;
    while (reader->Read(&page)) version = page.map_version();
    EXPECT_TRUE(reader->Finish().ok());
    return version;
  }

  std::set<uint64_t> FeatureIds() {
    std::set<uint64_t> ids;
    for (const pb::FusedFeature& f : Features()) ids.insert(f.id());
    return ids;
  }

  // The server's own record of every change after `since` (the core's change
  // feed, watch_hub.h): what a watch resumed from `since` must be sent.
  std::vector<service::ChangePtr> ChangesSince(uint64_t since) {
    service::WatchHub& hub = server_->core()->watch_hub();
    StatusOr<service::WatchHub::Subscription> sub = hub.Subscribe(since, [] {});
    EXPECT_TRUE(sub.ok()) << sub.status().ToString();
    if (!sub.ok()) return {};
    hub.Unsubscribe(sub->watcher);
    EXPECT_FALSE(sub->resync) << "the history does not reach back to version " << since;
    return sub->replay;
  }

  // `messages` are `changes`, each exactly once and in order, as an
  // unfiltered client holding the ids `held` is sent them: a feature new to it
  // added, one it holds updated, one gone removed (with `loose`, a resume's
  // catch-up, whether held or not). No change is missing or repeated, no id
  // appears twice in one message, versions strictly increase.
  static void ExpectExactly(const std::vector<pb::FeatureMapDelta>& messages,
                            const std::vector<service::ChangePtr>& changes, std::set<uint64_t> held,
                            bool loose) {
    size_t next = 0;
    for (const service::ChangePtr& c : changes) {
      SCOPED_TRACE("the change to version " + std::to_string(c->to_version));
      ASSERT_TRUE(c->planes.empty() && c->planes_gone.empty()) << "no planes in the room";
      std::vector<std::string> added, updated;
      std::vector<uint64_t> removed;
      for (const service::FusedView& v : c->lines) {
        pb::FusedFeature f;
        service::ToProto(v, &f);
        (held.insert(v.feature.id).second ? added : updated).push_back(f.SerializeAsString());
      }
      for (fusion::ClusterId id : c->lines_gone) {
        if (held.erase(id) > 0 || loose) removed.push_back(id);
      }
      if (added.empty() && updated.empty() && removed.empty()) continue;  // nothing to send
      ASSERT_LT(next, messages.size()) << "not sent";
      const pb::FeatureMapDelta& m = messages[next++];
      EXPECT_EQ(m.map_version(), c->to_version);
      EXPECT_FALSE(m.resync());
      EXPECT_FALSE(m.more());
      std::vector<std::string> got_added, got_updated;
      for (const auto& f : m.added()) got_added.push_back(f.SerializeAsString());
      for (const auto& f : m.updated()) got_updated.push_back(f.SerializeAsString());
      EXPECT_THAT(got_added, UnorderedElementsAreArray(added));
      EXPECT_THAT(got_updated, UnorderedElementsAreArray(updated));
      EXPECT_THAT(m.removed(), UnorderedElementsAreArray(removed));
    }
    EXPECT_EQ(next, messages.size()) << "messages beyond the changes";
    ExpectWellFormed(messages);
  }

  // Versions strictly increase (no message repeated) and no id appears twice
  // in one message.
  static void ExpectWellFormed(const std::vector<pb::FeatureMapDelta>& messages) {
    for (size_t i = 0; i < messages.size(); ++i) {
      const pb::FeatureMapDelta& m = messages[i];
      ASSERT_FALSE(m.more()) << "a change in several messages: not expected here";
      if (i > 0) {
        EXPECT_GT(m.map_version(), messages[i - 1].map_version()) << "message " << i;
      }
      std::set<uint64_t> ids;
      for (const auto& f : m.added()) EXPECT_TRUE(ids.insert(f.id()).second) << f.id();
      for (const auto& f : m.updated()) EXPECT_TRUE(ids.insert(f.id()).second) << f.id();
      for (uint64_t id : m.removed()) EXPECT_TRUE(ids.insert(id).second) << id;
    }
  }

  // The client's map equals GetFeatureMap's (same filter), feature by feature.
  void ExpectSameMap(WatchClient& watch, const pb::FeatureMapRequest& request = {}) {
    const uint64_t version = MapVersion();
    ASSERT_TRUE(watch.WaitForVersion(version)) << "the watch never reached version " << version;
    std::map<uint64_t, pb::FusedFeature> held = watch.Features();
    std::vector<pb::FusedFeature> served = Features(request);
    ASSERT_EQ(held.size(), served.size());
    for (const pb::FusedFeature& f : served) {
      ASSERT_EQ(held.count(f.id()), 1u) << "feature " << f.id() << " is missing";
      EXPECT_EQ(held[f.id()].SerializeAsString(), f.SerializeAsString()) << "feature " << f.id();
    }
  }
};

TEST_F(WatchTest, AWatcherSeesFeaturesAddedThenUpdatedWithIncreasingVersions) {
  WatchClient watch(stub_.get(), {});
  ASSERT_TRUE(watch.WaitFor([&] { return !watch.messages_.empty(); }));
  OneByOne(Walk("r1", 6));
  ExpectSameMap(watch);
  const auto messages = watch.Messages();
  ASSERT_GE(messages.size(), 2u);
  EXPECT_TRUE(messages[0].resync());
  EXPECT_EQ(messages[0].added_size(), 0) << "the map was empty";
  ExpectWellFormed(messages);
  // Every id is added once, before it is updated; nothing is removed.
  std::set<uint64_t> added;
  int updated = 0;
  for (size_t i = 1; i < messages.size(); ++i) {
    EXPECT_FALSE(messages[i].resync());
    for (const auto& f : messages[i].updated()) EXPECT_EQ(added.count(f.id()), 1u) << f.id();
    for (const auto& f : messages[i].added()) EXPECT_TRUE(added.insert(f.id()).second) << f.id();
    EXPECT_EQ(messages[i].removed_size(), 0);
    updated += messages[i].updated_size();
  }
  EXPECT_EQ(added, FeatureIds()) << "the four walls, each added once";
  EXPECT_EQ(added.size(), 4u);
  EXPECT_GT(updated, 0);
  EXPECT_EQ(watch.Features().size(), 4u);
}

TEST_F(WatchTest, AWatchOpenedLaterStartsWithTheFullMap) {
  Stream(Walk("r1", 6));
  const uint64_t version = MapVersion();
  WatchClient watch(stub_.get(), {});
  ASSERT_TRUE(watch.WaitForVersion(version));
  const auto messages = watch.Messages();
  ASSERT_EQ(messages.size(), 1u) << "the map, once, and nothing since";
  EXPECT_TRUE(messages[0].resync());
  EXPECT_EQ(messages[0].map_version(), version);
  EXPECT_EQ(messages[0].added_size(), 4);
  ExpectWellFormed(messages);
}

TEST_F(WatchTest, AResumeGetsExactlyTheMissedChanges) {
  server_.reset();
  config_.watch.max_watchers = 8;  // the witness and the hub's record below too
  StartServer();
  // A witness watches throughout: the live feed of every change, for
  // comparison with what the resumed watch is sent from the history.
  WatchClient witness(stub_.get(), {});
  WatchClient first(stub_.get(), {});
  OneByOne(Walk("r1", 4));
  const uint64_t v1 = MapVersion();
  ASSERT_TRUE(first.WaitForVersion(v1));
  first.Cancel();
  first.Finish();
  OneByOne(Walk("r1", 4, 5));
  OneByOne(Walk("r2", 3));

  WatchClient resumed(stub_.get(), Since(v1));
  ExpectSameMap(resumed);
  const auto missed = resumed.Messages();
  ASSERT_FALSE(missed.empty());
  for (const auto& m : missed) {
    EXPECT_FALSE(m.resync());
    EXPECT_GT(m.map_version(), v1);
  }
  // Exactly the changes after v1, each once: the resume took the ids of the
  // map as it is now (nothing changed since), and its catch-up reports every
  // id gone (watch_service.cc, StartFrom).
  const std::vector<service::ChangePtr> changes = ChangesSince(v1);
  ASSERT_GE(changes.size(), 7u) << "seven batches, each fused in a round of its own";
  ExpectExactly(missed, changes, FeatureIds(), /*loose=*/true);
  EXPECT_EQ(missed.back().map_version(), MapVersion());
  // The same changes as the witness got live after v1: versions, and the
  // features' states (a live client is told added or updated by what it held,
  // so only the union is compared).
  ASSERT_TRUE(witness.WaitForVersion(missed.back().map_version()));
  std::vector<pb::FeatureMapDelta> live;
  for (const auto& m : witness.Messages()) {
    if (m.map_version() > v1) live.push_back(m);
  }
  ASSERT_EQ(live.size(), missed.size());
  auto states = [](const pb::FeatureMapDelta& m) {
    std::vector<std::string> out;
    for (const auto& f : m.added()) out.push_back(f.SerializeAsString());
    for (const auto& f : m.updated()) out.push_back(f.SerializeAsString());
    return out;
  };
  for (size_t i = 0; i < live.size(); ++i) {
    EXPECT_EQ(missed[i].map_version(), live[i].map_version()) << i;
    EXPECT_THAT(states(missed[i]), UnorderedElementsAreArray(states(live[i]))) << i;
  }
  // Applied to what the first watch held, the missed changes give the map.
  std::map<uint64_t, pb::FusedFeature> held = first.features_;
  for (const auto& m : missed) {
    for (const auto& f : m.added()) held[f.id()] = f;
    for (const auto& f : m.updated()) held[f.id()] = f;
    for (uint64_t id : m.removed()) held.erase(id);
  }
  const auto served = Features();
  ASSERT_EQ(held.size(), served.size());
  for (const auto& f : served) {
    EXPECT_EQ(held[f.id()].SerializeAsString(), f.SerializeAsString());
    EXPECT_THAT(f.robots(), ::testing::ElementsAre("r1", "r2"));
  }
}

TEST_F(WatchTest, AResumeFromTheCurrentVersionSendsNothingUntilTheMapChanges) {
  OneByOne(Walk("r1", 4));
  const uint64_t v = MapVersion();
  WatchClient watch(stub_.get(), Since(v));
  OneByOne(Walk("r1", 1, 5));
  ExpectSameMap(watch);  // held only what changed: the four walls updated
  const auto messages = watch.Messages();
  ASSERT_FALSE(messages.empty());
  EXPECT_FALSE(messages.front().resync());
  EXPECT_GT(messages.front().map_version(), v);
  // Exactly the change since v, to a client that holds the four walls.
  const std::vector<service::ChangePtr> changes = ChangesSince(v);
  ASSERT_EQ(changes.size(), 1u) << "one batch, one round";
  ExpectExactly(messages, changes, FeatureIds(), /*loose=*/false);
  ASSERT_EQ(messages.size(), 1u);
  EXPECT_EQ(messages[0].added_size(), 0);
  EXPECT_EQ(messages[0].updated_size(), 4);
}

TEST_F(WatchTest, AVersionOlderThanTheHistoryGetsAResyncFirst) {
  server_.reset();
  config_.watch.history = 2;
  StartServer();
  OneByOne(Walk("r1", 3));
  const uint64_t old = MapVersion();
  OneByOne(Walk("r1", 5, 4));  // five changes: more than the history keeps
  WatchClient watch(stub_.get(), Since(old));
  ExpectSameMap(watch);
  const auto messages = watch.Messages();
  ASSERT_EQ(messages.size(), 1u) << "the map, once, and nothing since";
  EXPECT_TRUE(messages[0].resync());
  EXPECT_EQ(messages[0].added_size(), 4);
}

TEST_F(WatchTest, AVersionFromBeforeARestartGetsAResync) {
  OneByOne(Walk("r1", 3));
  const uint64_t old = MapVersion();
  OneByOne(Walk("r1", 2, 4));
  Restart();
  WatchClient watch(stub_.get(), Since(old));
  ExpectSameMap(watch);
  const auto messages = watch.Messages();
  ASSERT_EQ(messages.size(), 1u) << "the map, once, and nothing since";
  EXPECT_TRUE(messages[0].resync());
  EXPECT_EQ(messages[0].added_size(), 4);
}

TEST_F(WatchTest, FiltersByBboxKindAndRobot) {
  pb::WatchFeatureMapRequest bottom;  // only the wall along y = 0
  bottom.mutable_bbox()->mutable_min()->set_x(3);
  bottom.mutable_bbox()->mutable_min()->set_y(-1);
  bottom.mutable_bbox()->mutable_max()->set_x(7);
  bottom.mutable_bbox()->mutable_max()->set_y(1);
  pb::WatchFeatureMapRequest planes;
  planes.set_kind(pb::FEATURE_KIND_PLANE);
  pb::WatchFeatureMapRequest r2;
  r2.set_robot_id("r2");
  WatchClient by_box(stub_.get(), bottom), by_kind(stub_.get(), planes), by_robot(stub_.get(), r2);
  OneByOne(Walk("r1", 5));
  const uint64_t only_r1 = MapVersion();
  ASSERT_TRUE(by_robot.WaitFor([&] { return !by_robot.messages_.empty(); }));
  OneByOne(Walk("r2", 5));
  const uint64_t version = MapVersion();

  pb::FeatureMapRequest box_request;
  *box_request.mutable_bbox() = bottom.bbox();
  ExpectSameMap(by_box, box_request);
  EXPECT_EQ(by_box.Features().size(), 1u);
  for (const auto& m : by_box.Messages()) {
    for (const auto& f : m.added()) EXPECT_LT(std::abs(f.a().y()), 0.5);
    for (const auto& f : m.updated()) EXPECT_LT(std::abs(f.a().y()), 0.5);
  }
  // No vertical planes in the room: nothing but the (empty) first message.
  ASSERT_TRUE(by_kind.WaitFor([&] { return !by_kind.messages_.empty(); }));
  EXPECT_TRUE(by_kind.Features().empty());
  // The walls enter the robot filter when r2 first sees them: added then.
  ASSERT_TRUE(by_robot.WaitForVersion(version));
  EXPECT_EQ(by_robot.Features().size(), 4u);
  for (const auto& m : by_robot.Messages()) {
    if (m.added_size() > 0) {
      EXPECT_GT(m.map_version(), only_r1);
    }
    for (const auto& f : m.added()) EXPECT_THAT(f.robots(), ::testing::Contains("r2"));
  }
}

TEST_F(WatchTest, BadRequestsAreRefusedNamingTheField) {
  pb::WatchFeatureMapRequest inverted;
  inverted.mutable_bbox()->mutable_min()->set_x(5);
  inverted.mutable_bbox()->mutable_max()->set_x(1);
  pb::WatchFeatureMapRequest future = Since(1000000);
  pb::WatchFeatureMapRequest kind;
  kind.set_kind(static_cast<pb::FeatureKind>(9));
  pb::WatchFeatureMapRequest robot;
  robot.set_robot_id("no spaces");
  const std::vector<std::pair<pb::WatchFeatureMapRequest, std::string>> cases = {
      {inverted, "bbox"}, {future, "since_map_version"}, {kind, "kind"}, {robot, "robot_id"}};
  for (const auto& [request, field] : cases) {
    WatchClient watch(stub_.get(), request);
    const grpc::Status s = watch.Finish();
    EXPECT_EQ(s.error_code(), grpc::StatusCode::INVALID_ARGUMENT) << field;
    EXPECT_THAT(s.error_message(), HasSubstr(field));
  }
  // The server goes on.
  EXPECT_EQ(Stream(Walk("r1", 3)).size(), 3u);
}

TEST_F(WatchTest, WatchesBeyondTheLimitAreRefusedAndACancelledOneFreesItsPlace) {
  std::vector<std::unique_ptr<WatchClient>> open;
  for (int i = 0; i < 3; ++i) {
    open.push_back(std::make_unique<WatchClient>(stub_.get(), pb::WatchFeatureMapRequest{}));
    WatchClient& w = *open.back();
    ASSERT_TRUE(w.WaitFor([&] { return !w.messages_.empty(); }));
  }
  WatchClient refused(stub_.get(), {});
  const grpc::Status s = refused.Finish();
  EXPECT_EQ(s.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED);
  EXPECT_THAT(s.error_message(), HasSubstr("limits.max_watchers"));
  open.back()->Cancel();
  EXPECT_EQ(open.back()->Finish().error_code(), grpc::StatusCode::CANCELLED);
  // The place is free once the handler noticed (it looks every 250 ms).
  bool admitted = false;
  for (int attempt = 0; attempt < 200 && !admitted; ++attempt) {
    WatchClient again(stub_.get(), {});
    admitted = again.WaitFor([&] { return !again.messages_.empty() || again.done_; }) &&
               !again.Messages().empty();
    if (!admitted) std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  EXPECT_TRUE(admitted);
}

TEST_F(WatchTest, AWatcherThatNeverReadsDoesNotHoldIngestBack) {
  server_.reset();
  config_.watch.queue = 1;
  StartServer();
  WatchClient idle(stub_.get(), {}, /*read=*/false);
  // Every batch is acknowledged while the watcher reads nothing.
  for (int round = 0; round < 10; ++round) {
    const auto acks = Stream(Walk("r" + std::to_string(round), 20));
    ASSERT_EQ(acks.size(), 20u);
    for (const auto& a : acks) EXPECT_EQ(a.result(), pb::IngestAck::STORED);
  }
  // Once it reads, it catches up with the map (by changes or a resync).
  idle.Read();
  ExpectSameMap(idle);
}

TEST_F(WatchTest, ShutdownEndsOpenWatchesWithUnavailable) {
  Stream(Walk("r1", 4));
  WatchClient reading(stub_.get(), {});
  WatchClient idle(stub_.get(), {}, /*read=*/false);
  ASSERT_TRUE(reading.WaitFor([&] { return !reading.messages_.empty(); }));
  server_->Shutdown();  // returns once every call ended
  const grpc::Status s = reading.Finish();
  EXPECT_EQ(s.error_code(), grpc::StatusCode::UNAVAILABLE);
  EXPECT_THAT(s.error_message(), HasSubstr("since_map_version="));
  idle.Read();
  EXPECT_FALSE(idle.Finish().ok());
}

// --- On a FakeCore: changes a test publishes as the fuser would. ---

service::FusedView Line(uint64_t id, double x0, double y0, double x1, double y1,
                        std::vector<std::string> robots = {"r1"}) {
  service::FusedView v;
  v.feature.id = id;
  v.feature.segment = {{x0, y0}, {x1, y1}};
  v.feature.support = 3;
  v.robots = std::move(robots);
  return v;
}

class WatchFakeCoreTest : public ::testing::Test {
 protected:
  void Start(service::WatchOptions options = {}) {
    core_ = std::make_unique<FakeCore>(options);
    served_ = std::make_unique<ServedCore>(core_.get());
  }
  void TearDown() override { served_.reset(); }
  // The fuser's part: a change to `to`, the core's version moving with it.
  void Publish(uint64_t to, std::vector<service::FusedView> lines,
               std::vector<fusion::ClusterId> gone = {}) {
    auto c = std::make_shared<service::MapChange>();
    c->from_version = core_->map_version;
    c->to_version = to;
    c->lines = std::move(lines);
    c->lines_gone = std::move(gone);
    core_->map_version = to;
    core_->watch_hub().Publish(c);
  }

  pb::MapService::Stub* stub() const { return served_->stub(); }

  std::unique_ptr<FakeCore> core_;
  std::unique_ptr<ServedCore> served_;  // destroyed first
};

TEST_F(WatchFakeCoreTest, AFeatureLeavingTheBboxIsRemovedAndOneEnteringIsAdded) {
  Start();
  pb::WatchFeatureMapRequest request;
  request.mutable_bbox()->mutable_min()->set_x(0);
  request.mutable_bbox()->mutable_min()->set_y(0);
  request.mutable_bbox()->mutable_max()->set_x(5);
  request.mutable_bbox()->mutable_max()->set_y(5);
  WatchClient watch(stub(), request);
  ASSERT_TRUE(watch.WaitForVersion(1));
  Publish(2, {Line(10, 1, 1, 2, 1), Line(20, 8, 8, 9, 8)});  // 10 inside, 20 outside
  Publish(3, {Line(10, 7, 7, 8, 7), Line(20, 2, 2, 3, 2)});  // they swap
  Publish(4, {}, {20});                                      // 20 merged away
  ASSERT_TRUE(watch.WaitForVersion(4));
  const auto m = watch.Messages();
  ASSERT_EQ(m.size(), 4u);
  ASSERT_EQ(m[1].added_size(), 1);
  EXPECT_EQ(m[1].added(0).id(), 10u);
  EXPECT_THAT(m[2].removed(), ::testing::ElementsAre(10u));
  ASSERT_EQ(m[2].added_size(), 1);
  EXPECT_EQ(m[2].added(0).id(), 20u);
  EXPECT_THAT(m[3].removed(), ::testing::ElementsAre(20u));
  EXPECT_TRUE(watch.Features().empty());
}

TEST_F(WatchFakeCoreTest, ChangesOfNoInterestToTheFilterSendNothing) {
  Start();
  pb::WatchFeatureMapRequest request;
  request.set_robot_id("r2");
  WatchClient watch(stub(), request);
  ASSERT_TRUE(watch.WaitForVersion(1));
  Publish(2, {Line(10, 1, 1, 2, 1)});                // r1 only: nothing
  Publish(3, {Line(10, 1, 1, 2, 1, {"r1", "r2"})});  // r2 joins: added
  ASSERT_TRUE(watch.WaitForVersion(3));
  const auto m = watch.Messages();
  ASSERT_EQ(m.size(), 2u);
  EXPECT_EQ(m[1].map_version(), 3u);
  EXPECT_EQ(m[1].added_size(), 1);
}

TEST_F(WatchFakeCoreTest, AWatcherWhoseQueueOverflowsGetsAResyncAndPublishingNeverWaits) {
  service::WatchOptions options;
  options.queue = 2;
  options.history = 4;
  Start(options);
  WatchClient watch(stub(), {}, /*read=*/false);
  // Large changes fill the transport's buffers, then the handler's write
  // blocks and the queue overflows: Publish goes on regardless.
  // About 100 kB per change, 40 MB in all: more than any transport window.
  std::vector<std::string> robots;
  for (int r = 0; r < 8; ++r) robots.push_back("a-robot-with-a-long-name-" + std::to_string(r));
  std::vector<service::FusedView> many;
  for (uint64_t id = 1; id <= 400; ++id) many.push_back(Line(id, 0, 0, 1, 1.0 * id, robots));
  core_->features = many;
  for (uint64_t v = 2; v < 402; ++v) Publish(v, many);
  EXPECT_EQ(core_->watch_hub().version(), 401u);
  watch.Read();
  ASSERT_TRUE(watch.WaitForVersion(401));
  const auto m = watch.Messages();
  int resyncs = 0;
  for (const auto& msg : m) resyncs += msg.resync();
  EXPECT_GE(resyncs, 2) << "the first message and at least one after the overflow";
  EXPECT_LT(m.size(), 400u) << "dropped changes are not sent";
  EXPECT_EQ(watch.Features().size(), 400u);
}

TEST_F(WatchFakeCoreTest, ARecoveringCoreRefusesWatches) {
  Start();
  core_->SetReady(Status::Unavailable("recovering"));
  WatchClient watch(stub(), {});
  EXPECT_EQ(watch.Finish().error_code(), grpc::StatusCode::UNAVAILABLE);
}

}  // namespace
}  // namespace mapd::testing
