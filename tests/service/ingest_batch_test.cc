// ValidateBatch: what it accepts (normalised) and what it refuses, naming
// the field, the limit and the value; IngestLimits' own range.
#include "service/ingest_batch.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

#include "common/batches.h"

namespace mapd::service {
namespace {

using ::testing::HasSubstr;

class ValidateBatchTest : public ::testing::Test {
 protected:
  mapserver::v1::ObservationBatch Good() {
    return mapd::testing::RoomBatch("r1", "s1", 1, 2, 3, 0.5, &rng_);
  }
  Status Check(const mapserver::v1::ObservationBatch& b) {
    return ValidateBatch(b, limits_).status();
  }

  std::mt19937_64 rng_{7};
  IngestLimits limits_;
};

TEST_F(ValidateBatchTest, AcceptsAGoodBatchAndNormalisesTheQuaternion) {
  auto b = Good();
  b.mutable_t_frame_sensor()->mutable_rotation()->set_w(b.t_frame_sensor().rotation().w() * 1.0005);
  StatusOr<IngestBatch> r = ValidateBatch(b, limits_);
  ASSERT_TRUE(r.ok()) << r.status().ToString();
  EXPECT_NEAR(r->features.T_frame_sensor.rotation.norm(), 1.0, 1e-12);
  EXPECT_EQ(r->features.lines.size(), 4u);
  EXPECT_EQ(r->frame_kind, storage::FrameKind::kMap);
}

TEST_F(ValidateBatchTest, NamesANaNCoordinate) {
  auto b = Good();
  b.mutable_lines(2)->mutable_a()->set_y(std::nan(""));
  EXPECT_EQ(Check(b).code(), StatusCode::kInvalidArgument);
  EXPECT_THAT(Check(b).message(), HasSubstr("lines[2].a.y is NaN"));
}

TEST_F(ValidateBatchTest, NamesAnInfiniteTranslation) {
  auto b = Good();
  b.mutable_t_frame_sensor()->mutable_translation()->set_x(std::numeric_limits<double>::infinity());
  EXPECT_THAT(Check(b).message(), HasSubstr("T_frame_sensor.translation.x is infinite"));
}

TEST_F(ValidateBatchTest, RefusesAbsurdCoordinates) {
  auto b = Good();
  b.mutable_lines(0)->mutable_b()->set_x(5e6);
  EXPECT_EQ(Check(b).code(), StatusCode::kInvalidArgument);
  EXPECT_THAT(Check(b).message(), HasSubstr("lines[0].b.x"));
}

TEST_F(ValidateBatchTest, RefusesAZeroLengthSegment) {
  auto b = Good();
  *b.mutable_lines(1)->mutable_b() = b.lines(1).a();
  EXPECT_THAT(Check(b).message(), HasSubstr("lines[1] has zero length"));
}

// Issue 46: the fuser's work grows with a feature's length.
TEST_F(ValidateBatchTest, RefusesALineOrPlaneLongerThanTheLimit) {
  limits_.max_feature_length_m = 100.0;
  auto b = Good();
  b.mutable_lines(0)->mutable_a()->set_x(0);
  b.mutable_lines(0)->mutable_b()->set_x(99.0);
  b.mutable_lines(0)->mutable_a()->set_y(0);
  b.mutable_lines(0)->mutable_b()->set_y(0);
  b.mutable_lines(0)->mutable_a()->set_z(0);
  b.mutable_lines(0)->mutable_b()->set_z(0);
  EXPECT_TRUE(Check(b).ok()) << Check(b).ToString();
  b.mutable_lines(0)->mutable_b()->set_x(101.0);
  EXPECT_EQ(Check(b).code(), StatusCode::kInvalidArgument);
  EXPECT_THAT(Check(b).message(), HasSubstr("lines[0] is 101 m long; the limit is 100 m"));
  EXPECT_THAT(Check(b).message(), HasSubstr("limits.max_feature_length_m"));

  b = Good();
  auto* p = b.add_planes();
  p->mutable_normal()->set_z(1);
  p->add_boundary()->set_x(0);
  p->add_boundary()->set_x(60);
  p->add_boundary()->set_y(90);  // (60, 90): a 108 m diagonal
  p->mutable_boundary(2)->set_x(60);
  EXPECT_EQ(Check(b).code(), StatusCode::kInvalidArgument);
  EXPECT_THAT(Check(b).message(), HasSubstr("planes[0].boundary spans 108.167 m"));
}

TEST_F(ValidateBatchTest, RefusesANonUnitQuaternion) {
  auto b = Good();
  b.mutable_t_frame_sensor()->mutable_rotation()->set_w(2.0);
  EXPECT_EQ(Check(b).code(), StatusCode::kInvalidArgument);
  EXPECT_THAT(Check(b).message(), HasSubstr("T_frame_sensor.rotation has norm"));
}

TEST_F(ValidateBatchTest, RefusesAMissingPose) {
  auto b = Good();
  b.clear_t_frame_sensor();
  EXPECT_THAT(Check(b).message(), HasSubstr("T_frame_sensor"));
}

TEST_F(ValidateBatchTest, RefusesAPlaneWithTwoBoundaryPoints) {
  auto b = Good();
  auto* p = b.add_planes();
  p->mutable_normal()->set_x(1);
  p->add_boundary()->set_y(1);
  p->add_boundary()->set_z(1);
  EXPECT_EQ(Check(b).code(), StatusCode::kInvalidArgument);
  EXPECT_THAT(Check(b).message(), HasSubstr("planes[0].boundary has 2 points"));
}

TEST_F(ValidateBatchTest, RefusesANonUnitPlaneNormal) {
  auto b = Good();
  auto* p = b.add_planes();
  p->mutable_normal()->set_x(0.5);
  for (int i = 0; i < 3; ++i) p->add_boundary()->set_y(i);
  EXPECT_THAT(Check(b).message(), HasSubstr("planes[0].normal has norm"));
}

TEST_F(ValidateBatchTest, OverLimitBatchIsResourceExhausted) {
  auto b = Good();
  limits_.max_features_per_batch = 3;
  EXPECT_EQ(Check(b).code(), StatusCode::kResourceExhausted);
  EXPECT_EQ(Check(b).message(),
            "batch has 4 features (lines + planes); the limit is 3 (max_features_per_batch): "
            "split it");
}

// At the limit accepted, one over refused, lines and planes counted together:
// at the default and at the hard limit (kMaxFeaturesPerBatchHard, the feature
// id space).
TEST_F(ValidateBatchTest, TheFeatureLimitIsExactLinesAndPlanesTogether) {
  auto with = [&](int lines, int planes) {
    auto b = Good();
    b.clear_lines();
    for (int i = 0; i < lines; ++i) *b.add_lines() = Good().lines(0);
    for (int i = 0; i < planes; ++i) {
      auto* p = b.add_planes();
      p->mutable_normal()->set_x(1);
      for (int k = 0; k < 3; ++k) p->add_boundary()->set_y(k);
    }
    return b;
  };
  for (const uint32_t limit : {IngestLimits().max_features_per_batch, kMaxFeaturesPerBatchHard}) {
    SCOPED_TRACE(limit);
    limits_.max_features_per_batch = limit;
    ASSERT_TRUE(limits_.Validate().ok());
    const int n = static_cast<int>(limit);
    StatusOr<IngestBatch> at = ValidateBatch(with(n - 1, 1), limits_);
    ASSERT_TRUE(at.ok()) << at.status().ToString();
    EXPECT_EQ(at->features.lines.size() + at->features.planes.size(), limit);
    for (const auto& [lines, planes] : {std::pair{n + 1, 0}, {n, 1}, {0, n + 1}}) {
      const Status over = Check(with(lines, planes));
      EXPECT_EQ(over.code(), StatusCode::kResourceExhausted) << lines << " + " << planes;
      EXPECT_THAT(over.message(),
                  HasSubstr("batch has " + std::to_string(limit + 1) + " features"));
      EXPECT_THAT(over.message(),
                  HasSubstr("the limit is " + std::to_string(limit) + " (max_features_per_batch)"));
    }
  }
}

TEST_F(ValidateBatchTest, OverLimitPlaneBoundaryIsResourceExhausted) {
  limits_.max_boundary_points = 4;
  auto with_points = [&](int n) {
    auto b = Good();
    auto* p = b.add_planes();
    p->mutable_normal()->set_x(1);
    for (int i = 0; i < n; ++i) p->add_boundary()->set_y(i);
    return b;
  };
  StatusOr<IngestBatch> at = ValidateBatch(with_points(4), limits_);
  ASSERT_TRUE(at.ok()) << at.status().ToString();
  ASSERT_EQ(at->features.planes.size(), 1u);
  EXPECT_EQ(at->features.planes[0].boundary.size(), 4u);
  const Status over = Check(with_points(5));
  EXPECT_EQ(over.code(), StatusCode::kResourceExhausted);
  EXPECT_THAT(over.message(), HasSubstr("planes[0].boundary has 5 points; the limit is 4 "
                                        "(max_boundary_points)"));
}

TEST_F(ValidateBatchTest, RefusesBadIdsAndSeqZero) {
  auto b = Good();
  b.set_robot_id("");
  EXPECT_THAT(Check(b).message(), HasSubstr("robot_id"));
  b = Good();
  b.set_session_id("has space");
  EXPECT_THAT(Check(b).message(), HasSubstr("session_id"));
  b = Good();
  b.set_seq(0);
  EXPECT_THAT(Check(b).message(), HasSubstr("seq is 0"));
}

TEST(IngestLimitsTest, RefusesLimitsBeyondTheFeatureIdSpace) {
  IngestLimits l;
  EXPECT_TRUE(l.Validate().ok());
  // The feature id space: (observation id << kFeatureIdBits) | index.
  EXPECT_EQ(kMaxFeaturesPerBatchHard, 1u << kFeatureIdBits);
  l.max_features_per_batch = kMaxFeaturesPerBatchHard;
  EXPECT_TRUE(l.Validate().ok());
  const std::string range =
      "max_features_per_batch must be in [1, " + std::to_string(kMaxFeaturesPerBatchHard) + "]";
  for (const uint32_t bad : {kMaxFeaturesPerBatchHard + 1, 0u}) {
    l.max_features_per_batch = bad;
    const Status s = l.Validate();
    EXPECT_EQ(s.code(), StatusCode::kInvalidArgument) << bad;
    EXPECT_EQ(s.message(), range) << bad;
  }
}

}  // namespace
}  // namespace mapd::service
