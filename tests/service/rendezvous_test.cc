// Rendezvous hashing (service/rendezvous.h): the same answer everywhere, an
// even spread, and when an instance leaves only its maps move.
#include "service/rendezvous.h"

#include <gtest/gtest.h>

#include <map>
#include <string>
#include <vector>

namespace mapd::service {
namespace {

std::vector<std::string> Maps(int n) {
  std::vector<std::string> ids;
  for (int i = 0; i < n; ++i) ids.push_back("site-" + std::to_string(i));
  return ids;
}

TEST(RendezvousTest, TheAnswerIsFixedAndIndependentOfOrder) {
  const std::vector<std::string> a = {"mapd-a:50051", "mapd-b:50051", "mapd-c:50051"};
  const std::vector<std::string> b = {"mapd-c:50051", "mapd-a:50051", "mapd-b:50051"};
  for (const std::string& id : Maps(50)) EXPECT_EQ(RendezvousPick(id, a), RendezvousPick(id, b));
  // Pinned: every host and build must agree, so the weight may never change.
  EXPECT_EQ(RendezvousWeight("default", "mapd-a:50051"), 14540217699557190067ull);
  EXPECT_NE(RendezvousWeight("ab", "c"), RendezvousWeight("a", "bc"));
  EXPECT_EQ(RendezvousPick("default", {}), "");
  EXPECT_EQ(RendezvousPick("default", {"only"}), "only");
}

TEST(RendezvousTest, MapsSpreadEvenlyAndOnlyALeaversMapsMove) {
  const std::vector<std::string> three = {"a", "b", "c"};
  const std::vector<std::string> two = {"a", "c"};  // b left
  std::map<std::string, int> count;
  int moved = 0, of_b = 0;
  for (const std::string& id : Maps(3000)) {
    const std::string before = RendezvousPick(id, three), after = RendezvousPick(id, two);
    ++count[before];
    if (before == "b") ++of_b;
    if (before != after) {
      ++moved;
      EXPECT_EQ(before, "b") << id << " moved though its instance stayed";
    }
  }
  for (const auto& [instance, n] : count) {
    EXPECT_GT(n, 850) << instance;  // a third is 1000
    EXPECT_LT(n, 1150) << instance;
  }
  EXPECT_EQ(moved, of_b);
}

}  // namespace
}  // namespace mapd::service
