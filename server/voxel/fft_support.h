// The voxel library's FFTs (correlation_search.cc, yaw_refinement.cc): real-
// to-complex transforms in single precision (FFTW's fftwf) on grids of 2 or
// 3 dimensions, and the planner lock. Single precision: the grids hold 0/1
// and shares of a cell, and the correlations are only ranked.
#ifndef MAPD_VOXEL_FFT_SUPPORT_H_
#define MAPD_VOXEL_FFT_SUPPORT_H_

#include <algorithm>
#include <array>
#include <complex>
#include <cstddef>
#include <map>
#include <mutex>
#include <utility>
#include <vector>

#include "voxel/parallel.h"

struct fftwf_plan_s;  // fftw3.h's plan, kept out of this header

namespace mapd::voxel {

using Complex = std::complex<float>;

// a * conj(b), as std::complex computes it for finite values, but inline:
// GCC's complex product checks its result for NaN and calls out to
// __mulsc3 (C99 Annex G), which keeps the spectrum loops from vectorising.
// The spectra here are finite.
inline Complex MulConj(Complex a, Complex b) {
  return {a.real() * b.real() + a.imag() * b.imag(), a.imag() * b.real() - a.real() * b.imag()};
}

// FFTW's planner (plan creation and destruction) is not thread-safe; plan
// execution is. Every plan of the library is made and destroyed under this
// one lock, so merges may run concurrently.
std::mutex& FftwPlannerMutex();

// The smallest size >= n with only the factors 2, 3 and 5 (FFTW is fastest
// on those).
int FftSize(int n);

// One r2c / c2r plan pair on a row-major grid of `dims` (the last dimension
// is halved in the spectrum), with its own buffers: a transform reads and
// writes them in place, so a correlation keeps only the spectra it needs.
// sum_x f(x) g(x - s) = Inverse of (F * conj(G)), unnormalised (times
// real_size()).
class RealFft {
 public:
  // threads: ForwardInBox's and InverseRows' transforms run on that many
  // threads (1: the caller's alone). Their 1D transforms are split into
  // kParts fixed batches, each planned on its own, whatever the thread
  // count: the results are the same on any number of threads. Not FFTW's
  // own threads: on a 540 x 120 x 81 grid its estimated threaded plans
  // spent 25x the time of one thread waking threads (a campus crop pair
  // took 18 s instead of 3).
  explicit RealFft(const std::vector<int>& dims, int threads = 1);
  ~RealFft();
  RealFft(const RealFft&) = delete;
  RealFft& operator=(const RealFft&) = delete;

  // Makes this the transform of a grid of `dims` (as many dimensions, none
  // larger than the constructor's) on the same buffers. Why: fresh buffers
  // for every size cost page faults (zeroed by the kernel on first touch; on
  // the campus crops a third of the translation search when each yaw had
  // its own). The plans are made again; the buffers' contents are undefined.
  void Reshape(const std::vector<int>& dims);

  // Fills the real buffer with value(i) for every cell and transforms it;
  // returns the spectrum (valid until the next call).
  template <typename ValueAt>
  Complex* Forward(const ValueAt& value) {
    for (std::size_t i = 0; i < real_size_; ++i) real_[i] = static_cast<float>(value(i));
    ExecuteForward();
    return spectrum_;
  }
  // Forward for a 3D grid that is zero outside the corner box x < extent[0],
  // y < extent[1] (any z): value(i) is read only inside it, and the 1D
  // transforms of the rows and planes that hold only zeros are skipped. A
  // map's grid fills an eighth of its padded correlation grid or less, so
  // this does 19-62 % of the z and y passes (a forward transform ~27 % less
  // on the campus crops' 14M cells) and a quarter of the filling. The
  // spectrum is the whole transform's (the same 1D passes; bit for bit equal
  // to FFTW's own plan on the benchmark's grids, tested to 1e-4).
  template <typename ValueAt>
  Complex* ForwardInBox(const std::array<int, 2>& extent, const ValueAt& value) {
    const std::size_t n1 = static_cast<std::size_t>(dims_[1]),
                      n2 = static_cast<std::size_t>(dims_[2]);
    for (std::size_t x = 0; x < static_cast<std::size_t>(extent[0]); ++x) {
      for (std::size_t y = 0; y < static_cast<std::size_t>(extent[1]); ++y) {
        const std::size_t row = (x * n1 + y) * n2;
        for (std::size_t z = 0; z < n2; ++z) real_[row + z] = static_cast<float>(value(row + z));
      }
    }
    ExecuteForwardInBox(extent);
    return spectrum_;
  }
  // ForwardInBox with the rows filled by fill_row(x, y, row): the row's
  // dims[2] values, x < extent[0], y < extent[1] (a grid of another layout
  // copied in). The rows are filled on the transform's threads (fill_row is
  // called concurrently for different rows): the fill is also the first
  // touch of fresh buffer pages, whose zeroing by the kernel is then shared.
  template <typename FillRow>
  Complex* ForwardInBoxRows(const std::array<int, 2>& extent, const FillRow& fill_row) {
    const std::size_t n1 = static_cast<std::size_t>(dims_[1]),
                      n2 = static_cast<std::size_t>(dims_[2]);
    ParallelFor(static_cast<std::size_t>(std::max(extent[0], 0)), threads_,
                [&](std::size_t x, std::size_t) {
                  for (int y = 0; y < extent[1]; ++y) {
                    fill_row(static_cast<int>(x), y,
                             real_ + (x * n1 + static_cast<std::size_t>(y)) * n2);
                  }
                });
    ExecuteForwardInBox(extent);
    return spectrum_;
  }
  // The inverse of spectrum(), which it overwrites; valid until the next call.
  float* Inverse();

  // Half-open index ranges along one axis, ascending, within [0, dims).
  using Ranges = std::vector<std::pair<int, int>>;
  // Inverse() of a 3D grid for the rows (x, y, every z) with x in `xs` and y
  // in `ys` alone; the result's other rows are undefined. The y and z passes
  // skip the planes and rows outside: a correlation is zero at the shifts
  // where the two grids' content cannot meet (a fifth to a third of them on
  // the campus crops). The rows' values are Inverse()'s.
  float* InverseRows(const Ranges& xs, const Ranges& ys);

  Complex* spectrum() { return spectrum_; }
  std::size_t real_size() const { return real_size_; }
  std::size_t complex_size() const { return complex_size_; }

 private:
  void MakePlans();
  void DestroyPlans();
  void ExecuteForward();
  void ExecuteForwardInBox(std::array<int, 2> extent);

  // One pass of 1D transforms, as kParts plans over consecutive parts of
  // its batch (fewer when the batch is smaller), run on threads_.
  static constexpr int kParts = 8;
  using Pass = std::vector<fftwf_plan_s*>;
  void Execute(const Pass& pass) const;
  static void Destroy(Pass* pass);

  // The three passes of ForwardInBox for one extent (planned on first use).
  struct BoxPlans {
    Pass rows;     // r2c along z, x < extent[0], y < extent[1]
    Pass columns;  // along y, x < extent[0]
    Pass planes;   // along x, everywhere
  };

  // InverseRows' passes: along x everywhere, along y per x range, c2r along
  // z per (x range, y range) (planned on first use).
  Pass inverse_planes_;
  std::map<std::pair<int, int>, Pass> inverse_columns_;
  std::map<std::array<int, 4>, Pass> inverse_rows_;

  const int threads_;
  std::vector<int> dims_;
  std::vector<int> capacity_dims_;  // the constructor's, which sized the buffers
  std::map<std::array<int, 2>, BoxPlans> box_plans_;
  std::size_t real_size_ = 1, complex_size_ = 1;
  std::size_t real_capacity_ = 1, complex_capacity_ = 1;
  float* real_ = nullptr;
  Complex* spectrum_ = nullptr;
  fftwf_plan_s* forward_ = nullptr;
  fftwf_plan_s* inverse_ = nullptr;
};

}  // namespace mapd::voxel

#endif  // MAPD_VOXEL_FFT_SUPPORT_H_
