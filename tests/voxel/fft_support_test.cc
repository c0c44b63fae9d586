// The real FFT helpers against whole-grid transforms: forward in a box,
// inverse on rows, reshaping to a new size.
#include "voxel/fft_support.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <random>
#include <vector>

namespace mapd::voxel {
namespace {

// A grid that is random inside x < extent[0], y < extent[1] and zero outside.
std::vector<float> GridInBox(const std::array<int, 3>& n, const std::array<int, 2>& extent,
                             unsigned seed) {
  std::mt19937 random(seed);
  std::uniform_real_distribution<float> value(-1.0F, 1.0F);
  std::vector<float> grid(static_cast<std::size_t>(n[0]) * n[1] * n[2], 0.0F);
  for (int x = 0; x < extent[0]; ++x) {
    for (int y = 0; y < extent[1]; ++y) {
      for (int z = 0; z < n[2]; ++z)
        grid[(static_cast<std::size_t>(x) * n[1] + y) * n[2] + z] = value(random);
    }
  }
  return grid;
}

// ForwardInBox transforms only the rows and planes inside its box; the
// spectrum must be the whole grid's, whatever was in the buffers before
// (each box is run after another, larger one) and for boxes that are empty
// or the whole grid.
TEST(RealFftTest, ForwardInBoxIsTheWholeGridsTransform) {
  const std::array<int, 3> n = {12, 10, 9};
  RealFft fft({n[0], n[1], n[2]});
  const std::vector<std::array<int, 2>> extents = {{12, 10}, {5, 4}, {1, 10}, {12, 1},
                                                   {7, 7},   {0, 6}, {5, 4}};
  for (std::size_t k = 0; k < extents.size(); ++k) {
    const std::vector<float> grid = GridInBox(n, extents[k], static_cast<unsigned>(k));
    const Complex* full = fft.Forward([&](std::size_t i) { return grid[i]; });
    const std::vector<Complex> expected(full, full + fft.complex_size());
    // A value read outside the box would poison the spectrum.
    const Complex* pruned = fft.ForwardInBox(extents[k], [&](std::size_t i) {
      const std::size_t x = i / (static_cast<std::size_t>(n[1]) * n[2]);
      const std::size_t y = (i / n[2]) % n[1];
      const bool inside = x < static_cast<std::size_t>(extents[k][0]) &&
                          y < static_cast<std::size_t>(extents[k][1]);
      return inside ? grid[i] : NAN;
    });
    double worst = 0;
    for (std::size_t i = 0; i < fft.complex_size(); ++i) {
      worst = std::max(worst, static_cast<double>(std::abs(pruned[i] - expected[i])));
    }
    EXPECT_LT(worst, 1e-4) << "extent " << extents[k][0] << " x " << extents[k][1];
  }
}

// InverseRows must give Inverse()'s values on the rows asked for, with one or
// two ranges per axis, and leave the spectrum's other consumers unaffected
// (each call transforms a fresh product).
TEST(RealFftTest, InverseRowsIsTheInverseOnItsRows) {
  const std::array<int, 3> n = {12, 10, 9};
  RealFft fft({n[0], n[1], n[2]});
  const std::vector<float> grid = GridInBox(n, {12, 10}, 11);
  const Complex* f = fft.Forward([&](std::size_t i) { return grid[i]; });
  const std::vector<Complex> spectrum(f, f + fft.complex_size());
  std::copy(spectrum.begin(), spectrum.end(), fft.spectrum());
  const float* full = fft.Inverse();
  const std::vector<float> expected(full, full + fft.real_size());
  const std::vector<std::pair<RealFft::Ranges, RealFft::Ranges>> cases = {
      {{{0, 12}}, {{0, 10}}}, {{{0, 4}, {9, 12}}, {{0, 3}, {7, 10}}}, {{{2, 5}}, {{6, 10}}}};
  for (const auto& [xs, ys] : cases) {
    std::copy(spectrum.begin(), spectrum.end(), fft.spectrum());
    const float* rows = fft.InverseRows(xs, ys);
    int checked = 0;
    for (const auto& [x0, x1] : xs) {
      for (int x = x0; x < x1; ++x) {
        for (const auto& [y0, y1] : ys) {
          for (int y = y0; y < y1; ++y) {
            for (int z = 0; z < n[2]; ++z) {
              const std::size_t i = (static_cast<std::size_t>(x) * n[1] + y) * n[2] + z;
              ASSERT_NEAR(rows[i], expected[i], 1e-3) << "cell " << x << " " << y << " " << z;
              ++checked;
            }
          }
        }
      }
    }
    EXPECT_GT(checked, 0);
  }
}

// The passes run their fixed parts on the threads given: the spectrum and
// the inverse's rows are the same, bit for bit, on 1 and 3 threads (an odd
// last dimension, as the 540 x 120 x 81 campus grid on which FFTW's own
// threads were 25 times slower), and still the whole grid's transform.
TEST(RealFftTest, ThreadsChangeNothing) {
  const std::array<int, 3> n = {30, 24, 9};
  const std::array<int, 2> extent = {17, 13};
  const std::vector<float> grid = GridInBox(n, extent, 5);
  RealFft one({n[0], n[1], n[2]}, 1), three({n[0], n[1], n[2]}, 3);
  const Complex* whole = one.Forward([&](std::size_t i) { return grid[i]; });
  const std::vector<Complex> expected(whole, whole + one.complex_size());
  const auto row_of = [&](int x, int y, float* row) {
    const float* from = grid.data() + (static_cast<std::size_t>(x) * n[1] + y) * n[2];
    std::copy(from, from + n[2], row);
  };
  const Complex* a = one.ForwardInBoxRows(extent, row_of);
  const std::vector<Complex> spectrum(a, a + one.complex_size());
  const Complex* b = three.ForwardInBoxRows(extent, row_of);
  for (std::size_t i = 0; i < spectrum.size(); ++i) {
    ASSERT_EQ(spectrum[i], b[i]) << i;
    ASSERT_LT(std::abs(spectrum[i] - expected[i]), 1e-4) << i;
  }
  const RealFft::Ranges xs = {{0, 9}, {20, 30}}, ys = {{0, 24}};
  const float* rows_one = one.InverseRows(xs, ys);
  const float* rows_three = three.InverseRows(xs, ys);
  for (const auto& [x0, x1] : xs) {
    for (std::size_t i = static_cast<std::size_t>(x0) * n[1] * n[2];
         i < static_cast<std::size_t>(x1) * n[1] * n[2]; ++i) {
      ASSERT_EQ(rows_one[i], rows_three[i]) << i;
      // The unnormalised inverse of the grid's own spectrum.
      ASSERT_NEAR(rows_one[i], grid[i] * static_cast<float>(one.real_size()), 1e-2) << i;
    }
  }
}

// Reshape puts a smaller grid on the same buffers: its transforms, pruned or
// whole, forward or inverse, must be those of a RealFft made for that size,
// after the buffers held a larger grid's (and back to the larger size).
TEST(RealFftTest, ReshapedIsTheTransformOfTheNewSize) {
  RealFft fft({12, 10, 9});
  for (const std::array<int, 3>& n :
       std::vector<std::array<int, 3>>{{12, 10, 9}, {6, 10, 9}, {8, 5, 9}, {12, 10, 9}}) {
    fft.Reshape({n[0], n[1], n[2]});
    RealFft fresh({n[0], n[1], n[2]});
    ASSERT_EQ(fft.real_size(), fresh.real_size());
    ASSERT_EQ(fft.complex_size(), fresh.complex_size());
    const std::array<int, 2> extent = {n[0] / 2, n[1] - 1};
    const std::vector<float> grid = GridInBox(n, extent, static_cast<unsigned>(n[0] + n[1]));
    const auto at = [&](std::size_t i) { return grid[i]; };
    const Complex* expected = fresh.Forward(at);
    const Complex* pruned = fft.ForwardInBox(extent, at);
    double worst = 0;
    for (std::size_t i = 0; i < fft.complex_size(); ++i) {
      worst = std::max(worst, static_cast<double>(std::abs(pruned[i] - expected[i])));
    }
    EXPECT_LT(worst, 1e-4) << "size " << n[0] << " x " << n[1] << " x " << n[2];
    const float* round_trip = fft.InverseRows({{0, n[0]}}, {{0, n[1]}});
    for (std::size_t i = 0; i < grid.size(); ++i) {
      ASSERT_NEAR(round_trip[i] / static_cast<float>(fft.real_size()), grid[i], 1e-4)
          << "size " << n[0] << " x " << n[1] << " x " << n[2] << ", cell " << i;
    }
  }
}

}  // namespace
}  // namespace mapd::voxel
