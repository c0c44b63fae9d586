// A robot streaming to one map of a fleet of mapd sharing a database, for
// the failover test and the fleet benchmarks: a simulated batch every 20 ms
// (or as given) through a RobotClient given every instance's address (it
// follows redirects and fails over), with its acknowledgements counted.
#ifndef MAPD_TESTS_CLIENT_SUPPORT_STREAMING_ROBOT_H_
#define MAPD_TESTS_CLIENT_SUPPORT_STREAMING_ROBOT_H_

#include <grpcpp/grpcpp.h>

#include <atomic>
#include <chrono>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "client/robot/robot_client.h"
#include "client/sim_robot.h"

namespace mapd::testing {

inline std::shared_ptr<grpc::Channel> Connect(const std::string& address) {
  return grpc::CreateCustomChannel(address, grpc::InsecureChannelCredentials(),
                                   robot::RobotChannelArguments());
}

// One robot streaming to one map, a batch every `period`, until stopped;
// its id is "robot-<map>" unless given.
class StreamingRobot {
 public:
  StreamingRobot(const std::string& map, const std::vector<std::string>& addresses,
                 const std::string& robot_id = "",
                 std::chrono::milliseconds period = std::chrono::milliseconds(20))
      : map_(map) {
    robot::RobotClientOptions options;
    options.map_id = map;
    options.give_up_after = std::chrono::seconds(60);
    options.connect = Connect;
    options.addresses.assign(addresses.begin() + 1, addresses.end());
    client_ = std::make_unique<robot::RobotClient>(Connect(addresses[0]), options);
    client::SimRobotParams params;
    params.robot_id = robot_id.empty() ? "robot-" + map : robot_id;
    params.session_id = "s";
    sim_ = std::make_unique<client::SimRobot>(client::DefaultWorld(), params);
    thread_ = std::thread([this, period] {
      while (!stop_) {
        client_->Send(sim_->NextBatch());
        ++sent_;
        std::this_thread::sleep_for(period);
      }
    });
  }
  ~StreamingRobot() { Stop(); }

  void Stop() {
    stop_ = true;
    if (thread_.joinable()) thread_.join();
  }
  // Answers so far: stored and duplicate.
  uint64_t acked() const {
    const robot::IngestCounts c = client_->counts();
    return c.stored + c.duplicate;
  }
  uint64_t sent() const { return sent_; }
  robot::RobotClient& client() { return *client_; }
  const std::string& map() const { return map_; }

 private:
  const std::string map_;
  std::unique_ptr<robot::RobotClient> client_;
  std::unique_ptr<client::SimRobot> sim_;
  std::atomic<bool> stop_{false};
  std::atomic<uint64_t> sent_{0};
  std::thread thread_;
};

}  // namespace mapd::testing

#endif  // MAPD_TESTS_CLIENT_SUPPORT_STREAMING_ROBOT_H_
