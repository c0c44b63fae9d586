// FusionShare (service/fusion_share.h): which robot waits when the fuser is
// behind.
#include "service/fusion_share.h"

#include <gtest/gtest.h>

#include <string>

namespace mapd::service {
namespace {

// `n` observations of `robot` committed and not fused.
void Commit(FusionShare* share, const std::string& robot, int n) {
  for (int i = 0; i < n; ++i) share->Committed(robot);
}

// The fuser measured `robot` at cost_s per observation (and is done with them).
void Measure(FusionShare* share, const std::string& robot, double cost_s) {
  share->Committed(robot);
  share->Fused(robot, cost_s);
}

FusionShareOptions After(double after_s) {
  FusionShareOptions o;
  o.after_s = after_s;
  return o;
}

TEST(FusionShareTest, EqualLoadsAreNeverRefused) {
  FusionShare share(After(0.1));
  for (int r = 0; r < 8; ++r) Commit(&share, "r" + std::to_string(r), 1000 + 100 * r);
  for (int r = 0; r < 8; ++r) EXPECT_TRUE(share.Admit("r" + std::to_string(r)).ok()) << r;
  EXPECT_EQ(share.refused_total(), 0u);
}

// The city soak's shape: every robot at full rate (equal observations
// waiting), the ones in costlier streets at up to 3x the others' cost.
TEST(FusionShareTest, HonestDifferencesInCostAreNotRefused) {
  FusionShare share(FusionShareOptions{});
  for (int r = 0; r < 8; ++r) {
    const std::string robot = "r" + std::to_string(r);
    Measure(&share, robot, r < 2 ? 0.0003 : 0.0001);  // r0, r1: 3x
    Commit(&share, robot, 5000);                      // 4 s of work waiting in all
  }
  for (int r = 0; r < 8; ++r) EXPECT_TRUE(share.Admit("r" + std::to_string(r)).ok()) << r;
  EXPECT_EQ(share.refused_total(), 0u);
}

TEST(FusionShareTest, ARobotAloneIsNeverRefused) {
  FusionShare share(After(0.1));
  Commit(&share, "only", 100000);
  EXPECT_TRUE(share.Admit("only").ok());
}

TEST(FusionShareTest, NothingIsRefusedBelowTheThreshold) {
  FusionShare share(After(1.0));  // 1,000 observations at the unmeasured 1 ms
  Commit(&share, "busy", 900);
  Commit(&share, "quiet", 1);
  EXPECT_TRUE(share.Admit("busy").ok());
  Commit(&share, "busy", 200);
  EXPECT_EQ(share.Admit("busy").code(), StatusCode::kResourceExhausted);
  EXPECT_TRUE(share.Admit("quiet").ok());
  EXPECT_TRUE(share.Admit("newcomer").ok()) << "nothing waiting, nobody kept waiting";
}

TEST(FusionShareTest, TheWorkWaitingCountsNotTheObservations) {
  FusionShare share(After(0.05));
  Measure(&share, "costly", 0.010);  // 10 ms an observation
  Measure(&share, "cheap", 0.0001);  // 0.1 ms
  Commit(&share, "costly", 10);      // 100 ms waiting
  Commit(&share, "cheap", 100);      // 10 ms waiting, 10x as many observations
  const Status s = share.Admit("costly");
  EXPECT_EQ(s.code(), StatusCode::kResourceExhausted);
  EXPECT_NE(s.message().find("robot costly keeps the fuser busy: 10 of its observations"),
            std::string::npos)
      << s.message();
  EXPECT_TRUE(share.Admit("cheap").ok());
  ASSERT_EQ(share.Shares().size(), 2u);
  EXPECT_EQ(share.Shares()[1].robot, "costly");
  EXPECT_EQ(share.Shares()[1].refused, 1u);
  EXPECT_NEAR(share.Shares()[1].cost_per_obs_s, 0.010, 1e-12);
}

TEST(FusionShareTest, ARefusedRobotIsAdmittedOnceTheFuserCaughtUp) {
  FusionShare share(After(0.005));
  Commit(&share, "junk", 50);
  Commit(&share, "good", 2);
  ASSERT_FALSE(share.Admit("junk").ok());
  for (int i = 0; i < 42; ++i) share.Fused("junk", 0.001);  // 8 left: 4x the other's 2
  EXPECT_TRUE(share.Admit("junk").ok());
  share.Committed("junk");
  EXPECT_FALSE(share.Admit("junk").ok());  // 9 > 4 x 2
  share.Reset();                           // the fuser restarted: nothing waits
  EXPECT_TRUE(share.Admit("junk").ok());
}

// MapCore measures a random quarter of the observations: the others count as
// fused and leave the cost as measured.
TEST(FusionShareTest, AnUnmeasuredObservationIsFusedAndKeepsTheCost) {
  FusionShare share(After(1.0));
  Measure(&share, "r", 0.002);
  Commit(&share, "r", 3);
  share.Fused("r", std::nullopt);
  ASSERT_EQ(share.Shares().size(), 1u);
  EXPECT_EQ(share.Shares()[0].pending, 2u);
  EXPECT_NEAR(share.Shares()[0].cost_per_obs_s, 0.002, 1e-12);
  share.Fused("r", 0.004);
  EXPECT_NEAR(share.Shares()[0].cost_per_obs_s,
              (1.0 - FusionShare::kCostWeight) * 0.002 + FusionShare::kCostWeight * 0.004, 1e-12);
}

TEST(FusionShareTest, ZeroTurnsTheCheckOff) {
  FusionShare share(After(0.0));
  Commit(&share, "junk", 100000);
  Commit(&share, "good", 1);
  EXPECT_TRUE(share.Admit("junk").ok());
}

}  // namespace
}  // namespace mapd::service
