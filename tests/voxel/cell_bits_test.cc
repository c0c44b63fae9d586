#include "voxel/cell_bits.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <vector>

namespace mapd::voxel {
namespace {

TEST(CellBitsTest, SetCellsReadBackAndEveryOtherCellIsClear) {
  CellBits bits;
  const Eigen::Vector3i lo(-2, 3, -1), extent(5, 4, 3);
  ASSERT_TRUE(bits.Reset(lo, extent, 1000));
  // The box's two extreme corners and one cell inside.
  const std::vector<Eigen::Vector3i> set = {lo, lo + extent - Eigen::Vector3i::Ones(),
                                            Eigen::Vector3i(0, 4, 0)};
  for (const Eigen::Vector3i& c : set) bits.Set(c);
  int on = 0;
  for (int x = -4; x <= 4; ++x) {
    for (int y = 1; y <= 8; ++y) {
      for (int z = -3; z <= 3; ++z) {
        const Eigen::Vector3i c(x, y, z);
        const bool inside =
            (c.array() >= lo.array()).all() && (c.array() < (lo + extent).array()).all();
        EXPECT_EQ(bits.Contains(c), inside) << c.transpose();
        const bool expected = std::find(set.begin(), set.end(), c) != set.end();
        EXPECT_EQ(bits.Test(c), expected) << c.transpose();
        on += bits.Test(c);
      }
    }
  }
  EXPECT_EQ(on, 3);
}

TEST(CellBitsTest, ABoxAboveTheCapKeepsNoBits) {
  CellBits bits;
  EXPECT_FALSE(bits.Reset(Eigen::Vector3i::Zero(), Eigen::Vector3i(10, 10, 11), 1000));
  EXPECT_TRUE(bits.empty());
  EXPECT_FALSE(bits.Contains(Eigen::Vector3i(1, 1, 1)));
  EXPECT_FALSE(bits.Test(Eigen::Vector3i(1, 1, 1)));
  EXPECT_TRUE(bits.Reset(Eigen::Vector3i::Zero(), Eigen::Vector3i(10, 10, 10), 1000));
  EXPECT_FALSE(bits.empty());
}

}  // namespace
}  // namespace mapd::voxel
