// WriteHealth: how failed commits, a full disk and the probe's verdict set
// mapd's writability and the retry backoff.
#include "service/write_health.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <chrono>
#include <string>
#include <vector>

namespace mapd::service {
namespace {

using ::testing::HasSubstr;

// The health changes a listener sees, as "ok" or the failure's message.
struct Changes {
  std::vector<std::string> seen;
  explicit Changes(WriteHealth* health) {
    health->SetListener(
        [this](const Status& s) { seen.push_back(s.ok() ? "ok" : std::string(s.message())); });
  }
};

TEST(WriteHealthTest, AFailingCommitThenASuccessfulOneIsOneFailureAndOneRecovery) {
  WriteHealth health;
  Changes changes(&health);
  health.Record(Status::Internal("disk I/O error"));
  health.Record(Status::Internal("disk I/O error"));  // still failing: no second change
  EXPECT_FALSE(health.ok());
  EXPECT_THAT(health.status().message(), HasSubstr("disk I/O error"));
  health.Record(Status::Ok());
  EXPECT_TRUE(health.ok());
  EXPECT_EQ(changes.seen, (std::vector<std::string>{"disk I/O error", "ok"}));
}

TEST(WriteHealthTest, AVerdictOnTheRequestIsNoStorageFailure) {
  WriteHealth health;
  health.Record(Status::InvalidArgument("robot id is empty"));
  EXPECT_TRUE(health.ok());
}

// A commit retried after SQLITE_FULL can fit in the space its failed attempt
// freed; only the probe, which asks for real room, says the disk is no
// longer full (else health flaps while the disk stays full).
TEST(WriteHealthTest, AFullDiskIsOverOnlyWhenTheProbeSaysSo) {
  WriteHealth health;
  Changes changes(&health);
  health.Record(Status::ResourceExhausted("database or disk is full"));
  health.Record(Status::Ok());  // a retried batch group fitted
  EXPECT_FALSE(health.ok());
  EXPECT_THAT(health.status().message(), HasSubstr("full"));
  health.Record(Status::ResourceExhausted("the file system has 900 KiB free"),
                WriteHealth::Attempt::kProbe);
  health.Record(Status::Ok(), WriteHealth::Attempt::kCommit);
  EXPECT_FALSE(health.ok());
  health.Record(Status::Ok(), WriteHealth::Attempt::kProbe);
  EXPECT_TRUE(health.ok());
  EXPECT_EQ(changes.seen, (std::vector<std::string>{"database or disk is full", "ok"}));
}

TEST(WriteHealthTest, TheBackoffGrowsWithFailuresInARowAndStopsAtOneSecond) {
  WriteHealth health;
  health.Record(Status::Unavailable("database is locked"));
  const auto first = health.Backoff();
  for (int i = 0; i < 10; ++i) health.Record(Status::Unavailable("database is locked"));
  EXPECT_GT(health.Backoff(), first);
  EXPECT_LE(health.Backoff(), std::chrono::milliseconds(1000));
  health.Record(Status::Ok());
  EXPECT_TRUE(health.ok());
}

}  // namespace
}  // namespace mapd::service
