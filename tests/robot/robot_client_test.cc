// RobotClient against the real mapd: pipelined acks, rejections, reconnecting
// after the server died, giving up on a server that is not there.
#include "client/robot/robot_client.h"

#include <grpcpp/grpcpp.h>
#include <gtest/gtest.h>
#include <signal.h>

#include <atomic>

#include "client/sim_robot.h"
#include "common/process.h"
#include "common/temp_dir.h"

namespace mapd::robot {
namespace {

using client::DefaultWorld;
using client::SimRobot;
using client::SimRobotParams;

using mapd::testing::MapdProcess;
using std::chrono::seconds;

std::shared_ptr<grpc::Channel> Channel(const std::string& address) {
  return grpc::CreateChannel(address, grpc::InsecureChannelCredentials());
}

SimRobot Robot(const std::string& session) {
  SimRobotParams p;
  p.robot_id = "rc-robot";
  p.session_id = session;
  return SimRobot(DefaultWorld(), p);
}

class RobotClientTest : public ::testing::Test {
 protected:
  void SetUp() override {
    mapd_ = mapd::testing::StartMapd(dir_.File("map.db"));
    ASSERT_GT(mapd_.port, 0) << mapd_.log();
  }
  void TearDown() override {
    if (mapd_.pid > 0) mapd::testing::Stop(mapd_.pid, SIGKILL);
  }
  mapd::testing::TempDir dir_;
  MapdProcess mapd_;
};

TEST_F(RobotClientTest, PipelinesBatchesAndCountsAcks) {
  SimRobot robot = Robot("s1");
  RobotClient client(Channel(mapd_.address));
  for (int i = 0; i < 100; ++i) client.Send(robot.NextBatch());
  ASSERT_TRUE(client.Finish(seconds(10)).ok());
  const IngestCounts c = client.counts();
  EXPECT_EQ(c.sent, 100u);
  EXPECT_EQ(c.stored, 100u);
  EXPECT_EQ(c.duplicate, 0u);
  EXPECT_EQ(c.rejected, 0u);
  EXPECT_EQ(client.unacknowledged(), 0u);
}

TEST_F(RobotClientTest, ResentBatchesAreDuplicates) {
  SimRobot first = Robot("s1"), again = Robot("s1");
  {
    RobotClient client(Channel(mapd_.address));
    for (int i = 0; i < 10; ++i) client.Send(first.NextBatch());
    ASSERT_TRUE(client.Finish(seconds(10)).ok());
  }
  RobotClient client(Channel(mapd_.address));
  for (int i = 0; i < 10; ++i) client.Send(again.NextBatch());
  ASSERT_TRUE(client.Finish(seconds(10)).ok());
  EXPECT_EQ(client.counts().duplicate, 10u);
  EXPECT_EQ(client.counts().stored, 0u);
}

TEST_F(RobotClientTest, KeepsRejectionsAndGoesOn) {
  SimRobot robot = Robot("s1");
  RobotClient client(Channel(mapd_.address));
  client.Send(robot.NextBatch());
  mapserver::v1::ObservationBatch bad = robot.NextBatch();
  bad.mutable_t_frame_sensor()->mutable_translation()->set_y(std::nan(""));
  client.Send(bad);
  client.Send(robot.NextBatch());
  ASSERT_TRUE(client.Finish(seconds(10)).ok());
  EXPECT_EQ(client.counts().stored, 2u);
  ASSERT_EQ(client.counts().rejected, 1u);
  const std::vector<Rejection> rejections = client.rejections();
  ASSERT_EQ(rejections.size(), 1u);
  EXPECT_EQ(rejections[0].seq, 2u);
  EXPECT_EQ(rejections[0].code, grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_NE(rejections[0].message.find("translation.y is NaN"), std::string::npos)
      << rejections[0].message;
}

TEST_F(RobotClientTest, ReconnectsAndResendsAfterTheServerDied) {
  SimRobot robot = Robot("s1");
  RobotClient client(Channel(mapd_.address));
  for (int i = 0; i < 20; ++i) client.Send(robot.NextBatch());
  ASSERT_TRUE(client.WaitForAcks(seconds(10)));

  // The server dies; the robot goes on sending; the server comes back on the same port and db.
  mapd::testing::Stop(mapd_.pid, SIGKILL);
  mapd_.pid = -1;
  for (int i = 0; i < 20; ++i) client.Send(robot.NextBatch());
  mapd_ = mapd::testing::StartMapd(dir_.File("map.db"), {"--listen", mapd_.address});
  ASSERT_GT(mapd_.port, 0) << mapd_.log();

  const grpc::Status status = client.Finish(seconds(15));
  ASSERT_TRUE(status.ok()) << status.error_message();
  const IngestCounts c = client.counts();
  EXPECT_EQ(c.stored + c.duplicate, 40u);
  EXPECT_EQ(c.rejected, 0u);
  EXPECT_GE(c.reconnects, 1u);
}

TEST(RobotClientUnreachableTest, GivesUpWithTheReason) {
  RobotClientOptions options;
  options.give_up_after = std::chrono::milliseconds(500);
  options.initial_backoff = std::chrono::milliseconds(10);
  RobotClient client(Channel("127.0.0.1:1"), options);
  client.Send(Robot("s1").NextBatch());
  const grpc::Status status = client.Finish(seconds(10));
  EXPECT_EQ(status.error_code(), grpc::StatusCode::UNAVAILABLE) << status.error_message();
  EXPECT_EQ(client.unacknowledged(), 1u);
}

TEST_F(RobotClientTest, AMapTheServerDoesNotServeIsFinalAndNothingIsStored) {
  RobotClientOptions options;
  options.map_id = "site-9";  // this mapd serves one database: "default" only
  RobotClient client(Channel(mapd_.address), options);
  client.Send(Robot("s1").NextBatch());
  const grpc::Status status = client.Finish(seconds(10));
  EXPECT_EQ(status.error_code(), grpc::StatusCode::NOT_FOUND) << status.error_message();
  EXPECT_NE(status.error_message().find("'site-9'"), std::string::npos) << status.error_message();
  EXPECT_EQ(client.counts().stored, 0u);
  EXPECT_EQ(client.unacknowledged(), 1u);
}

TEST_F(RobotClientTest, TheDefaultMapByNameIsTheDefaultMap) {
  RobotClientOptions options;
  options.map_id = "default";
  RobotClient client(Channel(mapd_.address), options);
  client.Send(Robot("s1").NextBatch());
  ASSERT_TRUE(client.Finish(seconds(10)).ok());
  EXPECT_EQ(client.counts().stored, 1u);
}

// A mapd from before maps: Ingest stores everything, ListMaps is unimplemented
// (proto3 would skip the map it does not know).
class ServerBeforeMaps final : public mapserver::v1::MapService::Service {
 public:
  grpc::Status Ingest(grpc::ServerContext*,
                      grpc::ServerReaderWriter<mapserver::v1::IngestAck,
                                               mapserver::v1::ObservationBatch>* stream) override {
    mapserver::v1::ObservationBatch batch;
    while (stream->Read(&batch)) {
      ++stored;
      mapserver::v1::IngestAck ack;
      ack.set_session_id(batch.session_id());
      ack.set_seq(batch.seq());
      ack.set_result(mapserver::v1::IngestAck::STORED);
      stream->Write(ack);
    }
    return grpc::Status::OK;
  }
  std::atomic<int> stored{0};
};

TEST(RobotClientOldServerTest, AMapIsNeverSentToAServerThatKnowsNoMaps) {
  ServerBeforeMaps old;
  grpc::ServerBuilder builder;
  int port = 0;
  builder.AddListeningPort("127.0.0.1:0", grpc::InsecureServerCredentials(), &port);
  builder.RegisterService(&old);
  std::unique_ptr<grpc::Server> server = builder.BuildAndStart();
  ASSERT_GT(port, 0);
  const std::string address = "127.0.0.1:" + std::to_string(port);

  RobotClientOptions options;
  options.map_id = "site-7";
  RobotClient client(Channel(address), options);
  client.Send(Robot("s1").NextBatch());
  const grpc::Status status = client.Finish(seconds(10));
  EXPECT_EQ(status.error_code(), grpc::StatusCode::FAILED_PRECONDITION) << status.error_message();
  EXPECT_NE(status.error_message().find("before maps"), std::string::npos);
  EXPECT_EQ(old.stored.load(), 0);

  // Without a map the old server is used as before.
  RobotClient plain(Channel(address));
  plain.Send(Robot("s1").NextBatch());
  EXPECT_TRUE(plain.Finish(seconds(10)).ok());
  EXPECT_EQ(old.stored.load(), 1);
  server->Shutdown();
}

}  // namespace
}  // namespace mapd::robot
