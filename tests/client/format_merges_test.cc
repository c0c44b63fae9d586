// mapctl merge show: the matched corner pairs of a merge (count + first few
// in text, all of them in --json).
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>
#include <string>

#include "client/format.h"

namespace mapd::client {
namespace {

namespace pb = mapserver::v1;

pb::MergeRecord MergeWithCorners(int corners) {
  pb::MergeRecord m;
  m.set_id(3);
  m.set_state(pb::MERGE_STATE_PROPOSED);
  pb::SubmapAlignment* a = m.add_inputs();
  a->set_submap_id(1);
  a->mutable_t_reference_submap()->mutable_rotation()->set_w(1);
  pb::SubmapAlignment* b = m.add_inputs();
  b->set_submap_id(2);
  b->mutable_t_reference_submap()->mutable_rotation()->set_w(1);
  b->set_matched_corners(static_cast<uint32_t>(corners));
  for (int i = 0; i < corners; ++i) {
    pb::MatchedCorner* c = b->add_matched();
    c->mutable_in_submap()->set_x(i);
    c->mutable_in_submap()->set_y(0.5);
    c->mutable_in_reference()->set_x(i + 10);
    c->mutable_in_reference()->set_z(2.25);
  }
  return m;
}

TEST(FormatMergeRecordTest, ShowsTheCountAndTheFirstFiveMatchedCorners) {
  const std::string text = FormatMergeRecord(MergeWithCorners(7));
  EXPECT_NE(text.find("7 matched corner pairs (in submap -> in reference, m), first 5"),
            std::string::npos)
      << text;
  EXPECT_NE(text.find("(4.000, 0.500, 0.000) -> (14.000, 0.000, 2.250)"), std::string::npos);
  EXPECT_EQ(text.find("(5.000, 0.500, 0.000)"), std::string::npos);  // the 6th is left out

  const std::string two = FormatMergeRecord(MergeWithCorners(2));
  EXPECT_NE(two.find("2 matched corner pairs (in submap -> in reference, m)\n"), std::string::npos)
      << two;
  EXPECT_EQ(FormatMergeRecord(MergeWithCorners(0)).find("matched corner pair"), std::string::npos);
}

TEST(FormatMergeRecordTest, JsonHasEveryMatchedCorner) {
  const auto j = nlohmann::json::parse(FormatMergeRecordJson(MergeWithCorners(7)));
  EXPECT_TRUE(j["inputs"][0]["matched"].empty());
  const auto& matched = j["inputs"][1]["matched"];
  ASSERT_EQ(matched.size(), 7u);
  EXPECT_EQ(matched[6]["in_submap"], nlohmann::json({6.0, 0.5, 0.0}));
  EXPECT_EQ(matched[6]["in_reference"], nlohmann::json({16.0, 0.0, 2.25}));
}

}  // namespace
}  // namespace mapd::client
