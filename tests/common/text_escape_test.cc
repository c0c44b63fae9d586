// EscapeControlChars (server/common/text_escape.h): what a log line, an audit
// row or mapctl shows for untrusted text.
#include "common/text_escape.h"

#include <gtest/gtest.h>

namespace mapd {
namespace {

TEST(TextEscapeTest, PlainTextAndUtf8PassUnchanged) {
  EXPECT_EQ(EscapeControlChars("robot r1 session s-2.a_b"), "robot r1 session s-2.a_b");
  EXPECT_EQ(EscapeControlChars("K\xc3\xbc"
                               "che 3\xc2\xb0 \xe2\x82\xac \xf0\x9f\x98\x80"),
            "K\xc3\xbc"
            "che 3\xc2\xb0 \xe2\x82\xac \xf0\x9f\x98\x80");
  EXPECT_EQ(EscapeControlChars(""), "");
}

TEST(TextEscapeTest, LineBreaksAndTerminalEscapesBecomeVisible) {
  EXPECT_EQ(EscapeControlChars("a\nb\rc\td"), "a\\nb\\rc\\td");
  EXPECT_EQ(EscapeControlChars("\x1b[31mred\x1b[0m"), "\\x1b[31mred\\x1b[0m");
  EXPECT_EQ(EscapeControlChars(std::string("nul\0bel\x07"
                                           "del\x7f",
                                           12)),
            "nul\\x00bel\\x07del\\x7f");
}

TEST(TextEscapeTest, C1ControlsAndBidiOverridesAreEscaped) {
  EXPECT_EQ(EscapeControlChars("\xc2\x9b"
                               "2J"),
            "\\u009b2J");                                // CSI
  EXPECT_EQ(EscapeControlChars("\xc2\x85"), "\\u0085");  // NEL
  EXPECT_EQ(EscapeControlChars("ok \xe2\x80\xae"
                               "deneid"),
            "ok \\u202edeneid");
  EXPECT_EQ(EscapeControlChars("\xe2\x81\xa6x\xe2\x81\xa9"), "\\u2066x\\u2069");
}

TEST(TextEscapeTest, InvalidUtf8IsEscapedByteByByte) {
  EXPECT_EQ(EscapeControlChars("\x9b"
                               "2J"),
            "\\x9b2J");                                                       // a lone C1 byte
  EXPECT_EQ(EscapeControlChars("\xc3"), "\\xc3");                             // truncated
  EXPECT_EQ(EscapeControlChars("\xc0\x8a"), "\\xc0\\x8a");                    // overlong LF
  EXPECT_EQ(EscapeControlChars("\xed\xa0\x80"), "\\xed\\xa0\\x80");           // a surrogate
  EXPECT_EQ(EscapeControlChars("\xf4\x90\x80\x80"), "\\xf4\\x90\\x80\\x80");  // > U+10FFFF
}

TEST(TextEscapeTest, BackslashesAreDoubledOnlyWhenAsked) {
  EXPECT_EQ(EscapeControlChars("a\\nb"), "a\\nb");
  EXPECT_EQ(EscapeControlChars("a\\nb", /*escape_backslash=*/true), "a\\\\nb");
  EXPECT_EQ(EscapeControlChars("a\nb", /*escape_backslash=*/true), "a\\nb");
}

}  // namespace
}  // namespace mapd
