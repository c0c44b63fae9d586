// Retirement through a real mapd (fusion.retire_views, wall_retirement.h):
// simulated robots lap the demo floor while it changes, and the published
// map follows the building. Each test prints how many laps it took.
#include <grpcpp/grpcpp.h>
#include <gtest/gtest.h>
#include <signal.h>

#include <chrono>
#include <cstdio>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "client/robot/robot_client.h"
#include "client/sim_robot.h"
#include "common/process.h"
#include "common/temp_dir.h"
#include "mapserver/v1/map_service.grpc.pb.h"

// Named, so that a unity build with the other client tests sees no clash.
namespace mapd::client::retirement_e2e_test {
namespace {

namespace pb = mapserver::v1;
using std::chrono::seconds;

constexpr int kScansPerLap = 180;  // the 36 m loop at 0.2 m a scan
// DefaultWorld's wall 8: the box's south face, (9, 5.25)-(11, 5.25).
constexpr size_t kBoxSouthFace = 8;

class RetirementTest : public ::testing::Test {
 protected:
  void SetUp() override { ASSERT_NO_FATAL_FAILURE(Start()); }
  void Start() {
    // Snapshots every 500 observations: a restart loads the retirement
    // ledger from one and replays the rest.
    mapd_ = mapd::testing::StartMapd(dir_.File("map.db"), {"--snapshot.every_observations", "500"});
    ASSERT_GT(mapd_.port, 0) << mapd_.log();
    channel_ = grpc::CreateChannel(mapd_.address, grpc::InsecureChannelCredentials());
    stub_ = pb::MapService::NewStub(channel_);
  }
  // SIGKILL, then a new mapd on the same database, recovered.
  void Restart() {
    mapd::testing::Stop(mapd_.pid, SIGKILL);
    mapd_.pid = -1;
    ASSERT_NO_FATAL_FAILURE(Start());
    // From a snapshot mapd serves at once and replays the rest as a backlog.
    const auto deadline = std::chrono::steady_clock::now() + seconds(120);
    pb::Stats stats = Stats();
    while ((stats.replaying() || stats.fusion_backlog() > 0) &&
           std::chrono::steady_clock::now() < deadline) {
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
      stats = Stats();
    }
    ASSERT_FALSE(stats.replaying()) << mapd_.log();
  }
  void TearDown() override {
    if (mapd_.pid > 0) mapd::testing::Stop(mapd_.pid, SIGKILL);
  }

  // `robots` robots, spread around the loop, in `world`, with `change`.
  void AddRobots(int robots, const SimWorld& world, const WorldChange* change) {
    for (int i = 0; i < robots; ++i) {
      SimRobotParams p;
      p.robot_id = "retire-" + std::to_string(i + 1);
      p.session_id = "s";
      p.seed = 7 + static_cast<uint64_t>(i);
      p.start_fraction = static_cast<double>(i) / robots;
      if (change != nullptr) {
        p.has_change = true;
        p.change = *change;
      }
      robots_.emplace_back(world, p);
    }
  }

  // Every robot drives one lap (one after the other), then the fuser catches up.
  void Lap() {
    for (SimRobot& robot : robots_) {
      robot::RobotClient client(channel_);
      for (int s = 0; s < kScansPerLap; ++s) client.Send(robot.NextBatch());
      ASSERT_TRUE(client.Finish(seconds(30)).ok());
      ASSERT_EQ(client.counts().rejected, 0u);
    }
    const auto deadline = std::chrono::steady_clock::now() + seconds(30);
    while (Stats().fusion_backlog() > 0 && std::chrono::steady_clock::now() < deadline) {
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    ASSERT_EQ(Stats().fusion_backlog(), 0u);
  }

  pb::Stats Stats() {
    grpc::ClientContext ctx;
    pb::Stats stats;
    EXPECT_TRUE(stub_->GetStats(&ctx, {}, &stats).ok());
    return stats;
  }

  // The published map as text, one feature a line (id, ends, support).
  std::string MapText() {
    std::string text;
    for (const pb::FusedFeature& f : Features()) {
      char line[160];
      std::snprintf(line, sizeof(line), "%llu %.6f %.6f %.6f %.6f %u\n",
                    static_cast<unsigned long long>(f.id()), f.a().x(), f.a().y(), f.b().x(),
                    f.b().y(), f.support());
      text += line;
    }
    return text;
  }

  std::vector<pb::FusedFeature> Features() {
    grpc::ClientContext ctx;
    auto reader = stub_->GetFeatureMap(&ctx, pb::FeatureMapRequest());
    std::vector<pb::FusedFeature> out;
    pb::FeatureMapPage page;
    while (reader->Read(&page)) {
      out.insert(out.end(), page.features().begin(), page.features().end());
    }
    EXPECT_TRUE(reader->Finish().ok());
    return out;
  }

  // Whether a published feature runs along `wall` (ends within 0.3 m, along it within 0.1 m).
  bool Published(const Segment2& wall) {
    for (const pb::FusedFeature& f : Features()) {
      const Vec2 a(f.a().x(), f.a().y()), b(f.b().x(), f.b().y());
      const bool same = (a - wall.a).norm() < 0.3 && (b - wall.b).norm() < 0.3;
      const bool swapped = (a - wall.b).norm() < 0.3 && (b - wall.a).norm() < 0.3;
      if (same || swapped) return true;
    }
    return false;
  }

  mapd::testing::TempDir dir_;
  mapd::testing::MapdProcess mapd_;
  std::shared_ptr<grpc::Channel> channel_;
  std::unique_ptr<pb::MapService::Stub> stub_;
  std::vector<SimRobot> robots_;
};

TEST_F(RetirementTest, AWallTakenDownLeavesTheMapWithinALap) {
  const SimWorld world = DefaultWorld();
  const Segment2 face = world.walls[kBoxSouthFace];
  WorldChange change;
  change.after_laps = 2;
  change.remove = {kBoxSouthFace};
  AddRobots(3, world, &change);
  for (int lap = 1; lap <= 2; ++lap) {
    ASSERT_NO_FATAL_FAILURE(Lap());
    ASSERT_TRUE(Published(face)) << "lap " << lap;
  }
  ASSERT_EQ(Stats().retired_walls(), 0u);
  int laps_to_retire = 0;
  for (int lap = 3; lap <= 6; ++lap) {
    ASSERT_NO_FATAL_FAILURE(Lap());
    if (!Published(face) && laps_to_retire == 0) laps_to_retire = lap - 2;
  }
  std::printf("a wall taken down after lap 2 left the map after %d more lap(s)\n", laps_to_retire);
  EXPECT_EQ(laps_to_retire, 1);
  EXPECT_FALSE(Published(face)) << "it came back";
  EXPECT_GE(Stats().retired_walls(), 1u);
  // The other eleven walls stay.
  for (size_t i = 0; i < world.walls.size(); ++i) {
    if (i != kBoxSouthFace) {
      EXPECT_TRUE(Published(world.walls[i])) << "wall " << i;
    }
  }
  // A restart (snapshot plus replay) gives the same map, the wall still retired.
  const std::string before = MapText();
  const uint64_t retired = Stats().retired_walls();
  ASSERT_NO_FATAL_FAILURE(Restart());
  EXPECT_NE(mapd_.log().find("event=serving_while_replaying from=snapshot"), std::string::npos)
      << mapd_.log();
  EXPECT_EQ(MapText(), before);
  EXPECT_EQ(Stats().retired_walls(), retired);
}

TEST_F(RetirementTest, ADoorThatClosesAppearsAndNothingRetires) {
  // The box is open to the south (a 2 m doorway) until the door closes after lap 2.
  SimWorld world = DefaultWorld();
  const Segment2 door = world.walls[kBoxSouthFace];
  world.walls.erase(world.walls.begin() + kBoxSouthFace);
  WorldChange change;
  change.after_laps = 2;
  change.add = {door};
  AddRobots(3, world, &change);
  for (int lap = 1; lap <= 2; ++lap) ASSERT_NO_FATAL_FAILURE(Lap());
  ASSERT_FALSE(Published(door));
  int laps_to_appear = 0;
  for (int lap = 3; lap <= 5; ++lap) {
    ASSERT_NO_FATAL_FAILURE(Lap());
    if (Published(door) && laps_to_appear == 0) laps_to_appear = lap - 2;
  }
  std::printf("a door closed after lap 2 was in the map after %d more lap(s)\n", laps_to_appear);
  EXPECT_EQ(laps_to_appear, 1);
  // The box's other faces, seen from inside through the doorway before, are
  // hidden from inside now: hidden walls stay.
  EXPECT_EQ(Stats().retired_walls(), 0u);
  for (const Segment2& wall : world.walls) EXPECT_TRUE(Published(wall));
}

TEST_F(RetirementTest, AStaticFloorRetiresNothingOverTenLaps) {
  const SimWorld world = DefaultWorld();
  AddRobots(4, world, nullptr);
  for (int lap = 1; lap <= 10; ++lap) ASSERT_NO_FATAL_FAILURE(Lap());
  const pb::Stats stats = Stats();
  EXPECT_EQ(stats.retired_walls(), 0u);
  EXPECT_EQ(stats.fused_features(), world.walls.size());
  for (const Segment2& wall : world.walls) EXPECT_TRUE(Published(wall));
}

}  // namespace
}  // namespace mapd::client::retirement_e2e_test
