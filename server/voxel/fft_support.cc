#include "voxel/fft_support.h"

#include <fftw3.h>

#include <algorithm>
#include <cassert>
#include <tuple>

#include "voxel/large_array.h"

namespace mapd::voxel {

std::mutex& FftwPlannerMutex() {
  static std::mutex mutex;
  return mutex;
}

int FftSize(int n) {
  for (int m = std::max(n, 1);; ++m) {
    int r = m;
    for (int f : {2, 3, 5}) {
      while (r % f == 0) r /= f;
    }
    if (r == 1) return m;
  }
}

namespace {
using PlannerLock = std::lock_guard<std::mutex>;

// A pass of `count` 1D transforms as up to `parts` plans over consecutive
// parts of the batch: make(first, n) plans transforms [first, first + n).
template <typename Make>
std::vector<fftwf_plan_s*> SplitPass(int count, int parts, const Make& make) {
  std::vector<fftwf_plan_s*> pass;
  parts = std::max(1, std::min(parts, count));
  const PlannerLock lock(FftwPlannerMutex());
  for (int k = 0; k < parts; ++k) {
    const int first = static_cast<int>(static_cast<long>(count) * k / parts);
    const int end = static_cast<int>(static_cast<long>(count) * (k + 1) / parts);
    if (end > first) pass.push_back(make(first, end - first));
  }
  return pass;
}

// Cells of a real grid of `dims` and of its half spectrum.
std::pair<std::size_t, std::size_t> Sizes(const std::vector<int>& dims) {
  std::size_t real = 1, complex = 1;
  for (std::size_t k = 0; k < dims.size(); ++k) {
    real *= static_cast<std::size_t>(dims[k]);
    complex *= static_cast<std::size_t>(k + 1 < dims.size() ? dims[k] : dims[k] / 2 + 1);
  }
  return {real, complex};
}
}  // namespace

RealFft::RealFft(const std::vector<int>& dims, int threads)
    : threads_(threads), dims_(dims), capacity_dims_(dims) {
  std::tie(real_size_, complex_size_) = Sizes(dims);
  real_capacity_ = real_size_;
  complex_capacity_ = complex_size_;
  // Huge-page blocks (large_array.h), aligned beyond FFTW's SIMD needs.
  real_ = static_cast<float*>(internal::AllocateLarge(real_capacity_ * sizeof(float)));
  spectrum_ = static_cast<Complex*>(internal::AllocateLarge(complex_capacity_ * sizeof(Complex)));
  MakePlans();
}

RealFft::~RealFft() {
  DestroyPlans();
  internal::FreeLarge(real_, real_capacity_ * sizeof(float));
  internal::FreeLarge(spectrum_, complex_capacity_ * sizeof(Complex));
}

void RealFft::Reshape(const std::vector<int>& dims) {
  if (dims == dims_) return;
  // A grid no larger along any axis fits the buffers, the half spectrum too.
  assert(dims.size() == capacity_dims_.size());
  for (std::size_t k = 0; k < dims.size(); ++k) assert(dims[k] > 0 && dims[k] <= capacity_dims_[k]);
  DestroyPlans();
  dims_ = dims;
  std::tie(real_size_, complex_size_) = Sizes(dims);
  MakePlans();
}

void RealFft::MakePlans() {
  // fftwf_complex is float[2], laid out as std::complex<float> (FFTW manual 4.1.1).
  auto* spectrum = reinterpret_cast<fftwf_complex*>(spectrum_);
  const int rank = static_cast<int>(dims_.size());
  const PlannerLock lock(FftwPlannerMutex());
  forward_ = fftwf_plan_dft_r2c(rank, dims_.data(), real_, spectrum, FFTW_ESTIMATE);
  inverse_ = fftwf_plan_dft_c2r(rank, dims_.data(), spectrum, real_, FFTW_ESTIMATE);
}

void RealFft::Destroy(Pass* pass) {
  for (fftwf_plan_s* plan : *pass) fftwf_destroy_plan(plan);
  pass->clear();
}

void RealFft::Execute(const Pass& pass) const {
  ParallelFor(pass.size(), threads_, [&](std::size_t i, std::size_t) { fftwf_execute(pass[i]); });
}

void RealFft::DestroyPlans() {
  const std::lock_guard<std::mutex> lock(FftwPlannerMutex());
  fftwf_destroy_plan(forward_);
  fftwf_destroy_plan(inverse_);
  Destroy(&inverse_planes_);
  for (auto& [range, pass] : inverse_columns_) Destroy(&pass);
  for (auto& [ranges, pass] : inverse_rows_) Destroy(&pass);
  for (auto& [extent, p] : box_plans_) {
    Destroy(&p.rows);
    Destroy(&p.columns);
    Destroy(&p.planes);
  }
  forward_ = inverse_ = nullptr;
  inverse_columns_.clear();
  inverse_rows_.clear();
  box_plans_.clear();
}

void RealFft::ExecuteForward() { fftwf_execute(forward_); }

void RealFft::ExecuteForwardInBox(std::array<int, 2> extent) {
  const int n0 = dims_[0], n1 = dims_[1], n2c = dims_[2] / 2 + 1;
  extent = {std::clamp(extent[0], 0, n0), std::clamp(extent[1], 0, n1)};
  if (extent[0] == 0 || extent[1] == 0) {  // all zero
    std::fill(spectrum_, spectrum_ + complex_size_, Complex(0, 0));
    return;
  }
  auto* spectrum = reinterpret_cast<fftwf_complex*>(spectrum_);
  const std::size_t plane = static_cast<std::size_t>(n1) * n2c;
  auto found = box_plans_.find(extent);
  if (found == box_plans_.end()) {
    BoxPlans p;
    // Guru interface: a 1D transform of `length` (stride) repeated over
    // `loops` (count, input stride, output stride), in spectrum elements for
    // the complex passes; FFTW_ESTIMATE plans do not touch the buffers. Each
    // pass split along its outermost loop.
    p.rows = SplitPass(extent[0], kParts, [&](int x0, int nx) {
      const fftwf_iodim along_z = {dims_[2], 1, 1};
      const fftwf_iodim rows[2] = {{nx, n1 * dims_[2], n1 * n2c}, {extent[1], dims_[2], n2c}};
      return fftwf_plan_guru_dft_r2c(1, &along_z, 2, rows,
                                     real_ + static_cast<std::size_t>(x0) * n1 * dims_[2],
                                     spectrum + x0 * plane, FFTW_ESTIMATE);
    });
    p.columns = SplitPass(extent[0], kParts, [&](int x0, int nx) {
      const fftwf_iodim along_y = {n1, n2c, n2c};
      const fftwf_iodim columns[2] = {{nx, n1 * n2c, n1 * n2c}, {n2c, 1, 1}};
      fftwf_complex* part = spectrum + x0 * plane;
      return fftwf_plan_guru_dft(1, &along_y, 2, columns, part, part, FFTW_FORWARD, FFTW_ESTIMATE);
    });
    p.planes = SplitPass(n1 * n2c, kParts, [&](int k0, int nk) {
      const fftwf_iodim along_x = {n0, n1 * n2c, n1 * n2c};
      const fftwf_iodim planes[1] = {{nk, 1, 1}};
      return fftwf_plan_guru_dft(1, &along_x, 1, planes, spectrum + k0, spectrum + k0, FFTW_FORWARD,
                                 FFTW_ESTIMATE);
    });
    found = box_plans_.emplace(extent, std::move(p)).first;
  }
  // The passes read zeros where the rows were not transformed. On the
  // transform's threads: the first forward transform on fresh buffers is
  // their first touch here, and the kernel's zeroing of the pages is shared
  // (large_array.h, ResizeInParallel).
  ParallelFor(static_cast<std::size_t>(extent[0]), threads_, [&](std::size_t x, std::size_t) {
    std::fill_n(spectrum_ + x * plane + static_cast<std::size_t>(extent[1]) * n2c,
                static_cast<std::size_t>(n1 - extent[1]) * n2c, Complex(0, 0));
  });
  Complex* const tail = spectrum_ + static_cast<std::size_t>(extent[0]) * plane;
  ParallelRanges(static_cast<std::size_t>(spectrum_ + complex_size_ - tail), threads_,
                 [&](std::size_t begin, std::size_t end) {
                   std::fill(tail + begin, tail + end, Complex(0, 0));
                 });
  Execute(found->second.rows);
  Execute(found->second.columns);
  Execute(found->second.planes);
}

float* RealFft::Inverse() {
  fftwf_execute(inverse_);
  return real_;
}

float* RealFft::InverseRows(const Ranges& xs, const Ranges& ys) {
  const int n0 = dims_[0], n1 = dims_[1], n2 = dims_[2], n2c = dims_[2] / 2 + 1;
  auto* spectrum = reinterpret_cast<fftwf_complex*>(spectrum_);
  const std::size_t plane = static_cast<std::size_t>(n1) * n2c;
  // Planned on first use, each on the part of the buffers it transforms
  // (guru interface, as ExecuteForwardInBox; FFTW_ESTIMATE plans do not touch
  // the buffers).
  const auto planned = [&](auto* cache, const auto& key, auto&& make) -> const Pass& {
    auto found = cache->find(key);
    if (found == cache->end()) found = cache->emplace(key, make()).first;
    return found->second;
  };
  if (inverse_planes_.empty()) {
    inverse_planes_ = SplitPass(n1 * n2c, kParts, [&](int k0, int nk) {
      const fftwf_iodim along_x = {n0, n1 * n2c, n1 * n2c};
      const fftwf_iodim planes[1] = {{nk, 1, 1}};
      return fftwf_plan_guru_dft(1, &along_x, 1, planes, spectrum + k0, spectrum + k0,
                                 FFTW_BACKWARD, FFTW_ESTIMATE);
    });
  }
  Execute(inverse_planes_);
  // Plain ints, not structured bindings: C++17 lambdas cannot capture those.
  for (const std::pair<int, int>& x_range : xs) {
    const int x0 = x_range.first, x1 = x_range.second;
    if (x0 >= x1) continue;
    Execute(planned(&inverse_columns_, std::make_pair(x0, x1), [&] {
      return SplitPass(x1 - x0, kParts, [&](int first, int nx) {
        fftwf_complex* part = spectrum + static_cast<std::size_t>(x0 + first) * plane;
        const fftwf_iodim along_y = {n1, n2c, n2c};
        const fftwf_iodim columns[2] = {{nx, n1 * n2c, n1 * n2c}, {n2c, 1, 1}};
        return fftwf_plan_guru_dft(1, &along_y, 2, columns, part, part, FFTW_BACKWARD,
                                   FFTW_ESTIMATE);
      });
    }));
  }
  for (const std::pair<int, int>& x_range : xs) {
    for (const std::pair<int, int>& y_range : ys) {
      const int x0 = x_range.first, x1 = x_range.second;
      const int y0 = y_range.first, y1 = y_range.second;
      if (x0 >= x1 || y0 >= y1) continue;
      Execute(planned(&inverse_rows_, std::array<int, 4>{x0, x1, y0, y1}, [&] {
        return SplitPass(x1 - x0, kParts, [&](int first, int nx) {
          const std::size_t row =
              static_cast<std::size_t>(x0 + first) * n1 + static_cast<std::size_t>(y0);
          const fftwf_iodim along_z = {n2, 1, 1};
          const fftwf_iodim rows[2] = {{nx, n1 * n2c, n1 * n2}, {y1 - y0, n2c, n2}};
          return fftwf_plan_guru_dft_c2r(1, &along_z, 2, rows, spectrum + row * n2c,
                                         real_ + row * static_cast<std::size_t>(n2), FFTW_ESTIMATE);
        });
      }));
    }
  }
  return real_;
}

}  // namespace mapd::voxel
