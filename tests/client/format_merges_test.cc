// mapctl merge show: the matched corner pairs of a merge (count + first few
// in text, all of them in --json).
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
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

// The rest of the placing edge's evidence: a line under each placed input,
// "-" for a figure not measured; nothing for the reference input, nor for a
// merge recorded before the server kept it (no source).
TEST(FormatMergeRecordTest, ShowsThePlacingEdgesGateFigures) {
  pb::MergeRecord m = MergeWithCorners(0);
  pb::SubmapAlignment* b = m.mutable_inputs(1);
  b->set_source("correlation yaw 58.6 deg, peak 1");
  b->set_support_fraction(0.5312);
  b->set_shared_free_ratio(-1);
  b->set_restart_spread_voxels(1.234);
  b->set_second_residual_m(0.0613);
  const std::string text = FormatMergeRecord(m);
  EXPECT_NE(text.find("    placed by correlation yaw 58.6 deg, peak 1: support 0.531, shared free "
                      "-, restart spread 1.23 voxels, runner-up residual 0.061 m\n"),
            std::string::npos)
      << text;
  EXPECT_EQ(text.find("placed by"), text.rfind("placed by"));  // not for the reference

  const auto j = nlohmann::json::parse(FormatMergeRecordJson(m));
  EXPECT_EQ(j["inputs"][1]["source"], "correlation yaw 58.6 deg, peak 1");
  EXPECT_DOUBLE_EQ(j["inputs"][1]["restart_spread_voxels"].get<double>(), 1.234);
  EXPECT_DOUBLE_EQ(j["inputs"][1]["shared_free_ratio"].get<double>(), -1);

  // A figure that is not a number (a bad or old server) shows as not measured.
  b->set_support_fraction(std::nan(""));
  b->set_second_residual_m(std::numeric_limits<double>::infinity());
  EXPECT_NE(FormatMergeRecord(m).find("support -, shared free -"), std::string::npos);
  EXPECT_NE(FormatMergeRecord(m).find("runner-up residual -\n"), std::string::npos);

  b->clear_source();
  EXPECT_EQ(FormatMergeRecord(m).find("placed by"), std::string::npos);
}

TEST(FormatMergesTest, FreeTextFromTheServerStaysOnItsLine) {
  // A reason stored by an older mapd, which did not refuse control characters.
  pb::MergeRecord m = MergeWithCorners(0);
  m.set_state(pb::MERGE_STATE_REJECTED);
  m.set_reason("askew\n9  accepted  1,2\x1b[8m");
  m.set_decided_by("alice\r");
  m.set_decided_ns(1);
  pb::ListMergesResponse list;
  *list.add_merges() = m;
  for (const std::string& text : {FormatMergeRecord(m), FormatMerges(list)}) {
    EXPECT_NE(text.find("askew\\n9  accepted  1,2\\x1b[8m"), std::string::npos) << text;
    EXPECT_NE(text.find("alice\\r"), std::string::npos) << text;
    EXPECT_EQ(text.find('\x1b'), std::string::npos);
    EXPECT_EQ(text.find('\r'), std::string::npos);
  }
}

}  // namespace
}  // namespace mapd::client
