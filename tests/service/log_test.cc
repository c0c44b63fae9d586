// The logfmt writer (service/log.h): one call is one line, whatever the values.
#include "service/log.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <string>

namespace mapd::service {
namespace {

using ::testing::EndsWith;
using ::testing::HasSubstr;

std::string LogLine(std::initializer_list<LogField> fields) {
  ::testing::internal::CaptureStderr();
  Log(LogLevel::kWarn, "test_event", fields);
  return ::testing::internal::GetCapturedStderr();
}

TEST(LogTest, PlainValuesAreBareAndOthersQuoted) {
  const std::string line = LogLine({{"robot", "r1"}, {"error", "seq is 0"}, {"empty", ""}});
  EXPECT_THAT(line,
              HasSubstr(" level=warn event=test_event robot=r1 error=\"seq is 0\" empty=\"\""));
  EXPECT_THAT(line, EndsWith("\n"));
}

TEST(LogTest, ANewlineInAValueCannotStartALine) {
  // What an anonymous client sent as a session id (issue 43).
  const std::string line =
      LogLine({{"session", "s1\nts=2026-12-04T10:00:00.000Z level=info event=token_created"},
               {"peer", "ipv4:127.0.0.1:5000"}});
  EXPECT_EQ(line.find('\n'), line.size() - 1) << line;
  EXPECT_THAT(line, HasSubstr("session=\"s1\\nts=2026-12-04T10:00:00.000Z level=info "
                              "event=token_created\" peer=ipv4:127.0.0.1:5000"));
}

TEST(LogTest, TerminalEscapesQuotesAndBackslashesAreEscaped) {
  const std::string line =
      LogLine({{"a", "\x1b]0;owned\x07"}, {"b", "say \"hi\""}, {"c", "C:\\dir"}, {"d", "x\ry"}});
  EXPECT_THAT(line, HasSubstr("a=\"\\x1b]0;owned\\x07\""));
  EXPECT_THAT(line, HasSubstr("b=\"say \\\"hi\\\"\""));
  EXPECT_THAT(line, HasSubstr("c=\"C:\\\\dir\""));
  EXPECT_THAT(line, HasSubstr("d=\"x\\ry\""));
  for (char c : line.substr(0, line.size() - 1)) EXPECT_GE(static_cast<unsigned char>(c), 0x20);
}

}  // namespace
}  // namespace mapd::service
