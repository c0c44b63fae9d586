// The stored observation blob: round trip, and every truncation or absurd
// count refused without reading past the end or allocating.
#include "storage/observation_codec.h"

#include <gtest/gtest.h>

namespace mapd::storage {
namespace {

geometry::SensorObservation Sample() {
  geometry::SensorObservation obs;
  obs.lines.push_back({{1, 2, 3}, {4, 5, 6}});
  geometry::PlaneFeature p;
  p.normal = {1, 0, 0};
  p.offset = -2.5;
  p.boundary = {{2.5, 0, 0}, {2.5, 1, 0}, {2.5, 1, 2}};
  obs.planes.push_back(p);
  return obs;
}

TEST(ObservationCodecTest, RoundTripsLinesAndPlanes) {
  std::string payload;
  EncodeFeatures(Sample(), &payload);
  geometry::SensorObservation back;
  ASSERT_TRUE(DecodeFeatures(payload, &back).ok());
  ASSERT_EQ(back.lines.size(), 1u);
  EXPECT_EQ(back.lines[0].b, Eigen::Vector3d(4, 5, 6));
  ASSERT_EQ(back.planes.size(), 1u);
  EXPECT_EQ(back.planes[0].offset, -2.5);
  EXPECT_EQ(back.planes[0].boundary[2], Eigen::Vector3d(2.5, 1, 2));
}

TEST(ObservationCodecTest, RefusesEveryTruncationWithoutReadingPastTheEnd) {
  std::string payload;
  EncodeFeatures(Sample(), &payload);
  for (size_t n = 0; n < payload.size(); ++n) {
    geometry::SensorObservation back;
    const Status s = DecodeFeatures(std::string_view(payload.data(), n), &back);
    EXPECT_EQ(s.code(), StatusCode::kInternal) << "length " << n;
  }
}

TEST(ObservationCodecTest, RefusesAHugeCountBeforeAllocating) {
  std::string payload;
  EncodeFeatures(Sample(), &payload);
  payload[4] = '\xff';  // n_lines low byte -> far more lines than bytes
  payload[7] = '\x7f';
  geometry::SensorObservation back;
  EXPECT_EQ(DecodeFeatures(payload, &back).code(), StatusCode::kInternal);
}

}  // namespace
}  // namespace mapd::storage
