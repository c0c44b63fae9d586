// ExpectSameOutcome: two merges of the same inputs computed differently (on
// other thread counts, from prepared views) must agree figure for figure and
// byte for byte.
#ifndef MAPD_TESTS_VOXEL_SUPPORT_SAME_OUTCOME_H_
#define MAPD_TESTS_VOXEL_SUPPORT_SAME_OUTCOME_H_

#include <gtest/gtest.h>

#include <cstddef>

#include "voxel/merge.h"

namespace mapd::testing {

inline void ExpectSameOutcome(const voxel::MergeOutcome& one, const voxel::MergeOutcome& other) {
  ASSERT_EQ(one.alignments.size(), other.alignments.size());
  for (std::size_t i = 0; i < one.alignments.size(); ++i) {
    EXPECT_TRUE(one.alignments[i].T_reference_submap.matrix() ==
                other.alignments[i].T_reference_submap.matrix())
        << one.alignments[i].T_reference_submap.matrix() << "\nvs\n"
        << other.alignments[i].T_reference_submap.matrix();
  }
  ASSERT_EQ(one.pairs.size(), other.pairs.size());
  for (std::size_t i = 0; i < one.pairs.size(); ++i) {
    EXPECT_EQ(one.pairs[i].residual_m, other.pairs[i].residual_m);
    EXPECT_EQ(one.pairs[i].overlap_score, other.pairs[i].overlap_score);
    EXPECT_EQ(one.pairs[i].support_fraction, other.pairs[i].support_fraction);
    EXPECT_EQ(one.pairs[i].reason, other.pairs[i].reason);
    EXPECT_EQ(one.pairs[i].hypotheses_tried, other.pairs[i].hypotheses_tried);
  }
  EXPECT_EQ(one.corners, other.corners);
  EXPECT_EQ(one.occupied_voxels, other.occupied_voxels);
  EXPECT_TRUE(one.merged_bt == other.merged_bt) << "the merged maps differ";
}

}  // namespace mapd::testing

#endif  // MAPD_TESTS_VOXEL_SUPPORT_SAME_OUTCOME_H_
