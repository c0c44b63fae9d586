// CellBits, the bit grid of the correlation search: cells and rows set and
// read back across word boundaries, and the size cap.
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

TEST(CellBitsTest, SetRowSetsExactlyItsCellsAcrossWordBoundaries) {
  CellBits bits;
  const Eigen::Vector3i lo(-5, 0, 0), extent(150, 2, 2);  // rows of 150 bits
  ASSERT_TRUE(bits.Reset(lo, extent, 1000));
  bits.SetRow(Eigen::Vector3i(-3, 1, 0), 129);  // 133 cells, over three words
  bits.SetRow(Eigen::Vector3i(7, 0, 1), 7);     // one cell
  for (int z = 0; z < 2; ++z) {
    for (int y = 0; y < 2; ++y) {
      for (int x = -5; x < 145; ++x) {
        const bool expected =
            (y == 1 && z == 0 && x >= -3 && x <= 129) || (x == 7 && y == 0 && z == 1);
        EXPECT_EQ(bits.Test(Eigen::Vector3i(x, y, z)), expected) << x << " " << y << " " << z;
      }
    }
  }
}

}  // namespace
}  // namespace mapd::voxel
