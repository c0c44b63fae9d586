#include "voxel/fft_support.h"

#include <fftw3.h>

#include <algorithm>

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

RealFft::RealFft(const std::vector<int>& dims) {
  for (std::size_t k = 0; k < dims.size(); ++k) {
    real_size_ *= static_cast<std::size_t>(dims[k]);
    complex_size_ *= static_cast<std::size_t>(k + 1 < dims.size() ? dims[k] : dims[k] / 2 + 1);
  }
  real_ = fftwf_alloc_real(real_size_);
  // fftwf_complex is float[2], laid out as std::complex<float> (FFTW manual 4.1.1).
  auto* spectrum = fftwf_alloc_complex(complex_size_);
  spectrum_ = reinterpret_cast<Complex*>(spectrum);
  const int rank = static_cast<int>(dims.size());
  const std::lock_guard<std::mutex> lock(FftwPlannerMutex());
  forward_ = fftwf_plan_dft_r2c(rank, dims.data(), real_, spectrum, FFTW_ESTIMATE);
  inverse_ = fftwf_plan_dft_c2r(rank, dims.data(), spectrum, real_, FFTW_ESTIMATE);
}

RealFft::~RealFft() {
  {
    const std::lock_guard<std::mutex> lock(FftwPlannerMutex());
    fftwf_destroy_plan(forward_);
    fftwf_destroy_plan(inverse_);
  }
  fftwf_free(real_);
  fftwf_free(spectrum_);
}

void RealFft::ExecuteForward() { fftwf_execute(forward_); }

float* RealFft::Inverse() {
  fftwf_execute(inverse_);
  return real_;
}

}  // namespace mapd::voxel
