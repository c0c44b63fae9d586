// FusionParams validation (each refusal names its field, boundaries accepted)
// and the names of the corner modes and pairings.
#include "fusion/params.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

namespace mapd::fusion {
namespace {

using ::testing::HasSubstr;

TEST(FusionParamsTest, DefaultsAreValid) { EXPECT_TRUE(FusionParams().Validate().ok()); }

TEST(FusionParamsTest, RefusalsNameTheField) {
  FusionParams p;
  p.eta_m = -0.1;
  EXPECT_EQ(p.Validate().code(), StatusCode::kInvalidArgument);
  EXPECT_THAT(p.Validate().message(), HasSubstr("eta_m"));

  p = FusionParams();
  p.gamma = 1.5;
  EXPECT_THAT(p.Validate().message(), HasSubstr("gamma"));

  p = FusionParams();
  p.delta_rad = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THAT(p.Validate().message(), HasSubstr("delta_rad"));

  p = FusionParams();
  p.min_support = 0;
  EXPECT_THAT(p.Validate().message(), HasSubstr("min_support"));

  p = FusionParams();
  p.max_plane_tilt_rad = 2.0;
  EXPECT_THAT(p.Validate().message(), HasSubstr("max_plane_tilt_rad"));

  p = FusionParams();
  p.snap_m = std::numeric_limits<double>::infinity();
  EXPECT_THAT(p.Validate().message(), HasSubstr("snap_m"));

  p = FusionParams();
  p.chain_max_rms_m = -0.01;
  EXPECT_THAT(p.Validate().message(), HasSubstr("chain_max_rms_m"));

  p = FusionParams();
  p.chain_max_sse_ratio = 1.5;
  EXPECT_THAT(p.Validate().message(), HasSubstr("chain_max_sse_ratio"));

  p = FusionParams();
  p.max_component_nodes = 15;
  EXPECT_THAT(p.Validate().message(), HasSubstr("max_component_nodes"));

  p = FusionParams();
  p.max_link_candidates = (1u << 20) + 1;
  EXPECT_THAT(p.Validate().message(), HasSubstr("max_link_candidates"));

  p = FusionParams();
  p.max_wall_pieces = 15;
  EXPECT_THAT(p.Validate().message(), HasSubstr("max_wall_pieces"));
  p.max_wall_pieces = (1u << 20) + 1;
  EXPECT_THAT(p.Validate().message(), HasSubstr("max_wall_pieces"));

  p = FusionParams();
  p.evidence_range_m = 0.0;
  EXPECT_THAT(p.Validate().message(), HasSubstr("evidence_range_m"));
  p.evidence_range_m = 1001.0;
  EXPECT_THAT(p.Validate().message(), HasSubstr("evidence_range_m"));
}

// The cost caps change bounded results (on maps that reach them): a snapshot
// taken under other caps must not load.
TEST(FusionParamsTest, TheCostCapsAreInTheKey) {
  const FusionParams defaults;
  FusionParams p = defaults;
  p.max_component_nodes = 512;
  EXPECT_NE(FusionParamsKey(p), FusionParamsKey(defaults));
  p = defaults;
  p.max_link_candidates = 512;
  EXPECT_NE(FusionParamsKey(p), FusionParamsKey(defaults));
  p = defaults;
  p.evidence_range_m = 40.0;
  EXPECT_NE(FusionParamsKey(p), FusionParamsKey(defaults));
  p = defaults;
  p.max_wall_pieces = 512;
  EXPECT_NE(FusionParamsKey(p), FusionParamsKey(defaults));
}

TEST(FusionParamsTest, BoundaryValuesAreAccepted) {
  FusionParams p;
  p.gamma = 0.0;
  p.eta_m = 0.0;
  p.snap_m = 0.0;
  p.min_support = 1;
  p.chain_max_rms_m = 0.0;  // guard off
  p.chain_max_sse_ratio = 0.0;
  EXPECT_TRUE(p.Validate().ok());
  p.gamma = 1.0;
  EXPECT_TRUE(p.Validate().ok());
}

TEST(CornerModeTest, NamesRoundTrip) {
  for (CornerMode mode : {CornerMode::kMidpoint, CornerMode::kIntersection}) {
    CornerMode parsed = CornerMode::kMidpoint;
    ASSERT_TRUE(ParseCornerMode(CornerModeName(mode), &parsed).ok());
    EXPECT_EQ(parsed, mode);
  }
  CornerMode parsed = CornerMode::kMidpoint;
  const Status s = ParseCornerMode("nearest", &parsed);
  EXPECT_EQ(s.code(), StatusCode::kInvalidArgument);
  EXPECT_THAT(s.message(), HasSubstr("nearest"));
}

TEST(CornerPairingTest, NamesRoundTrip) {
  for (CornerPairing pairing : {CornerPairing::kMutualNearest, CornerPairing::kGreedy}) {
    CornerPairing parsed = CornerPairing::kGreedy;
    ASSERT_TRUE(ParseCornerPairing(CornerPairingName(pairing), &parsed).ok());
    EXPECT_EQ(parsed, pairing);
  }
  CornerPairing parsed = CornerPairing::kMutualNearest;
  const Status s = ParseCornerPairing("optimal", &parsed);
  EXPECT_EQ(s.code(), StatusCode::kInvalidArgument);
  EXPECT_THAT(s.message(), HasSubstr("optimal"));
  FusionParams p;
  p.corner_pairing = static_cast<CornerPairing>(7);
  EXPECT_THAT(p.Validate().message(), HasSubstr("corner_pairing"));
  FusionParams greedy;
  greedy.corner_pairing = CornerPairing::kGreedy;
  EXPECT_NE(FusionParamsKey(greedy), FusionParamsKey(FusionParams()));
}

}  // namespace
}  // namespace mapd::fusion
