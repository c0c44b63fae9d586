// Which addresses and Host headers the web view treats as loopback (web/loopback.h).
#include "service/loopback.h"

#include <gtest/gtest.h>

namespace mapd::service {
namespace {

TEST(LoopbackTest, BoundAddressesAreJudgedByWhatTheyAre) {
  for (const char* a :
       {"127.0.0.1", "127.1", "127.0.0.2", "localhost", "::1", "::ffff:127.0.0.1"}) {
    EXPECT_TRUE(IsLoopbackAddress(a)) << a;
  }
  for (const char* a :
       {"0.0.0.0", "::", "10.0.0.1", "192.168.1.2", "2001:db8::1", "no-such-host.invalid"}) {
    EXPECT_FALSE(IsLoopbackAddress(a)) << a;
  }
}

TEST(LoopbackTest, HostHeadersMustNameLoopbackLiterally) {
  for (const char* h : {"127.0.0.1", "127.0.0.1:8080", "127.1:8080", "localhost", "localhost:80",
                        "[::1]", "[::1]:8080", "[::ffff:127.0.0.1]:1"}) {
    EXPECT_TRUE(IsLoopbackHost(h)) << h;
  }
  for (const char* h :
       {"", "evil.example", "evil.example:80", "127.0.0.1.evil.example", "localhost.evil.example",
        "10.0.0.1:80", "[::2]:80", "[::1", "[::1]x", "::1"}) {
    EXPECT_FALSE(IsLoopbackHost(h)) << h;
  }
}

}  // namespace
}  // namespace mapd::service
