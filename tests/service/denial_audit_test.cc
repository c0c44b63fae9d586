// The per-identity limit on denial rows (service/denial_audit.h).
#include "service/denial_audit.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

namespace mapd::service {
namespace {

using ::testing::HasSubstr;

constexpr int64_t kMinuteNs = 60'000'000'000;

storage::AuditEntry Denial(const std::string& who, const std::string& action) {
  storage::AuditEntry e;
  e.who = who;
  e.role = "reader";
  e.action = action;
  e.result = "denied: ...";
  return e;
}

TEST(DenialAuditLimiterTest, ABurstIsRecordedThenCountedPerIdentity) {
  DenialAuditLimiter limiter(10);
  int written = 0;
  for (int i = 0; i < 500; ++i) written += limiter.Admit(Denial("dash", "CreateToken"), i);
  EXPECT_EQ(written, 10);
  // Another identity has a bucket of its own.
  EXPECT_TRUE(limiter.Admit(Denial("alice", "CreateToken"), 500));
  // Nothing is due before a row may be written again ...
  EXPECT_TRUE(limiter.TakeSummaries(1000).empty());
  // ... and after 6 s (a tenth of a minute) one summary per action.
  for (int i = 0; i < 7; ++i) limiter.Admit(Denial("dash", "MergeSubmaps"), 2000);
  const std::vector<storage::AuditEntry> rows = limiter.TakeSummaries(kMinuteNs / 10 + 2000);
  ASSERT_EQ(rows.size(), 2u);
  EXPECT_EQ(rows[0].action, "CreateToken");
  EXPECT_EQ(rows[0].who, "dash");
  EXPECT_EQ(rows[0].role, "reader");
  EXPECT_THAT(rows[0].result, HasSubstr("denied: 490 more denials of CreateToken by dash"));
  EXPECT_THAT(rows[1].result, HasSubstr("7 more denials of MergeSubmaps"));
  EXPECT_TRUE(limiter.TakeSummaries(kMinuteNs / 10 + 3000).empty());
}

TEST(DenialAuditLimiterTest, ASteadyFloodWritesAtTheRatePerMinute) {
  DenialAuditLimiter limiter(10);
  int rows = 0;
  // One denial every 10 ms for 10 minutes, summaries taken every second.
  for (int64_t t = 0; t < 10 * kMinuteNs; t += 10'000'000) {
    rows += limiter.Admit(Denial("dash", "CreateToken"), t);
    if (t % 1'000'000'000 == 0) rows += static_cast<int>(limiter.TakeSummaries(t).size());
  }
  EXPECT_LE(rows, 10 + 10 * 10 + 1);
  EXPECT_GE(rows, 10 * 10);
}

TEST(DenialAuditLimiterTest, ShutdownWritesWhatIsCountedAndIdleIdentitiesAreForgotten) {
  DenialAuditLimiter limiter(2);
  for (int i = 0; i < 5; ++i) limiter.Admit(Denial("dash", "CreateToken"), 0);
  std::vector<storage::AuditEntry> rows = limiter.TakeSummaries(1, /*all=*/true);
  ASSERT_EQ(rows.size(), 1u);
  EXPECT_THAT(rows[0].result, HasSubstr("3 more denials"));
  // A minute later the bucket is full and nothing is pending: forgotten, and
  // the next denial is recorded at once.
  EXPECT_TRUE(limiter.TakeSummaries(2 * kMinuteNs).empty());
  EXPECT_TRUE(limiter.Admit(Denial("dash", "CreateToken"), 2 * kMinuteNs));
}

}  // namespace
}  // namespace mapd::service
