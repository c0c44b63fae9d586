#include "voxel/yaw_refinement.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <complex>
#include <cstdint>
#include <memory>
#include <utility>

#include "voxel/fft_support.h"
#include "voxel/large_array.h"
#include "voxel/parallel.h"

namespace mapd::voxel {
namespace {

constexpr double kRadPerDeg = M_PI / 180.0;
// The spectrum of `values` into `out`.
void Transform(RealFft& fft, const LargeVector<float>& values, LargeVector<Complex>* out) {
  const Complex* s = fft.Forward([&](std::size_t i) { return values[i]; });
  out->assign(s, s + fft.complex_size());
}

// sum_x f(x) g(x - s) for every shift s (unnormalised), from the spectra of f
// and g; valid until the next transform.
const float* Correlate(RealFft& fft, const LargeVector<Complex>& f, const LargeVector<Complex>& g) {
  Complex* s = fft.spectrum();
  for (std::size_t i = 0; i < fft.complex_size(); ++i) s[i] = MulConj(f[i], g[i]);
  return fft.Inverse();
}

// Structure columns and data columns of one map on the padded image.
class ColumnImage {
 public:
  ColumnImage(int nx, int ny, double pixel_m) : nx_(nx), ny_(ny), pixel_m_(pixel_m) {
    const std::size_t size = static_cast<std::size_t>(nx) * ny;
    lowest_.resize(size);
    above_.resize(size);
    structure_.resize(size);
    data_.resize(size);
  }

  // `points` (levelled, metres) turned by `yaw` about +z, with `origin` at
  // the image's corner.
  void Rasterise(const std::vector<Eigen::Vector3d>& points, double yaw,
                 const Eigen::Vector2d& origin, const YawRefinementParams& params) {
    std::fill(lowest_.begin(), lowest_.end(), 1e30F);
    std::fill(above_.begin(), above_.end(), 0);
    const double c = std::cos(yaw), s = std::sin(yaw);
    pixel_.resize(points.size());
    for (std::size_t k = 0; k < points.size(); ++k) {
      const Eigen::Vector3d& p = points[k];
      const double x = c * p.x() - s * p.y(), y = s * p.x() + c * p.y();
      const int ix = static_cast<int>(std::floor((x - origin.x()) / pixel_m_));
      const int iy = static_cast<int>(std::floor((y - origin.y()) / pixel_m_));
      if (ix < 0 || iy < 0 || ix >= nx_ || iy >= ny_) {
        pixel_[k] = -1;
        continue;
      }
      pixel_[k] = static_cast<std::int64_t>(ix) * ny_ + iy;
      float& low = lowest_[static_cast<std::size_t>(pixel_[k])];
      low = std::min(low, static_cast<float>(p.z()));
    }
    for (std::size_t k = 0; k < points.size(); ++k) {
      if (pixel_[k] < 0) continue;
      const auto i = static_cast<std::size_t>(pixel_[k]);
      const double height = points[k].z() - lowest_[i];
      if (height > params.band_low_m && height <= params.band_high_m) ++above_[i];
    }
    structures_ = 0;
    for (std::size_t i = 0; i < data_.size(); ++i) {
      data_[i] = lowest_[i] < 1e29F ? 1.0F : 0.0F;
      structure_[i] = above_[i] >= params.min_voxels_in_band ? 1.0F : 0.0F;
      structures_ += structure_[i];
    }
  }

  // 1 where a set pixel lies within `radius` pixels along both axes; valid
  // until the next call (the buffers are kept: a refinement dilates ~100
  // images, and fresh ones of a campus crop cost page faults each time).
  const LargeVector<float>& Dilated(const LargeVector<float>& in, int radius) {
    LargeVector<float>& rows = rows_scratch_;
    LargeVector<float>& out = dilated_;
    rows.assign(in.size(), 0.0F);
    out.assign(in.size(), 0.0F);
    for (int x = 0; x < nx_; ++x) {
      for (int y = 0; y < ny_; ++y) {
        if (in[Index(x, y)] == 0) continue;
        for (int d = std::max(0, y - radius); d <= std::min(ny_ - 1, y + radius); ++d) {
          rows[Index(x, d)] = 1.0F;
        }
      }
    }
    for (int x = 0; x < nx_; ++x) {
      for (int y = 0; y < ny_; ++y) {
        if (rows[Index(x, y)] == 0) continue;
        for (int d = std::max(0, x - radius); d <= std::min(nx_ - 1, x + radius); ++d) {
          out[Index(d, y)] = 1.0F;
        }
      }
    }
    return out;
  }

  const LargeVector<float>& structure() const { return structure_; }
  const LargeVector<float>& data() const { return data_; }
  double structures() const { return structures_; }

 private:
  std::size_t Index(int x, int y) const { return static_cast<std::size_t>(x) * ny_ + y; }

  int nx_, ny_;
  double pixel_m_;
  LargeVector<float> lowest_;
  LargeVector<int> above_;
  LargeVector<float> structure_, data_;
  LargeVector<std::int64_t> pixel_;            // each point's pixel, -1 outside
  LargeVector<float> rows_scratch_, dilated_;  // Dilated's
  double structures_ = 0;
};

// A data pixel reaches this far (pixels): a sensor sees a surface from the
// columns in front of it, and a turned column lands in a neighbour.
constexpr int kDataRadius = 2;

}  // namespace

Status YawRefinementParams::Validate() const {
  if (!(window_deg >= 0 && window_deg <= 90) || !(coarse_step_deg >= 1 && coarse_step_deg <= 30)) {
    return Status::InvalidArgument(
        "yaw_refinement.window_deg must be in [0, 90] and coarse_step_deg in [1, 30]");
  }
  if (!(pixel_voxels >= 1 && pixel_voxels <= 64) || max_pixels < 1000 || max_pixels > 100'000'000) {
    return Status::InvalidArgument(
        "yaw_refinement.pixel_voxels must be in [1, 64] and max_pixels in [1000, 100000000]");
  }
  if (!(band_low_m >= 0 && band_low_m < band_high_m && band_high_m <= 100) ||
      min_voxels_in_band < 1 || min_voxels_in_band > 1000) {
    return Status::InvalidArgument(
        "yaw_refinement.band_low_m and band_high_m must satisfy 0 <= low < high <= 100 and "
        "min_voxels_in_band be in [1, 1000]");
  }
  if (!(min_change_deg >= 0 && min_change_deg <= 90) || max_added < 0 || max_added > 100) {
    return Status::InvalidArgument(
        "yaw_refinement.min_change_deg must be in [0, 90] and max_added in [0, 100]");
  }
  if (!(min_overlap_fraction > 0 && min_overlap_fraction <= 1)) {
    return Status::InvalidArgument("yaw_refinement.min_overlap_fraction must be in (0, 1]");
  }
  return Status::Ok();
}

StatusOr<std::vector<double>> RefineYaws(const VoxelGrid& a, const Eigen::Matrix3d& R_a,
                                         const VoxelGrid& b, const Eigen::Matrix3d& R_b,
                                         const std::vector<double>& yaws,
                                         double finest_resolution_m,
                                         const YawRefinementParams& params,
                                         YawRefinementStats* stats, int threads) {
  MAPD_RETURN_IF_ERROR(params.Validate());
  if (!(finest_resolution_m > 0)) return Status::InvalidArgument("resolution must be > 0");
  for (double yaw : yaws) {
    // A NaN or infinite yaw would turn every column into an undefined pixel index.
    if (!std::isfinite(yaw)) return Status::InvalidArgument("yaw candidates must be finite");
  }
  if (!params.enabled || a.empty() || b.empty() || yaws.empty()) return yaws;

  // a levelled in its box; b levelled about its centroid, so that any yaw
  // keeps it within a circle.
  std::vector<Eigen::Vector3d> points_a, points_b;
  points_a.reserve(a.num_occupied());
  points_b.reserve(b.num_occupied());
  Eigen::AlignedBox2d box_a;
  for (const Eigen::Vector3d& c : a.occupied_centres()) {
    points_a.push_back(R_a * c);
    box_a.extend(points_a.back().head<2>());
  }
  Eigen::Vector3d centroid_b = Eigen::Vector3d::Zero();
  for (const Eigen::Vector3d& c : b.occupied_centres()) centroid_b += R_b * c;
  centroid_b /= static_cast<double>(b.num_occupied());
  centroid_b.z() = 0;  // heights stay as they are: columns compare them within themselves
  double radius_b = 0;
  for (const Eigen::Vector3d& c : b.occupied_centres()) {
    points_b.push_back(R_b * c - centroid_b);
    radius_b = std::max(radius_b, points_b.back().head<2>().norm());
  }
  // The column edge, grown (as SearchTranslations grows its cell) until the
  // padded image fits max_pixels.
  double pixel = params.pixel_voxels * finest_resolution_m;
  int nx = 0, ny = 0;
  for (int attempt = 0;; ++attempt) {
    const int span_b = static_cast<int>(std::ceil(2 * radius_b / pixel)) + 2;
    nx = FftSize(static_cast<int>(std::ceil(box_a.sizes().x() / pixel)) + 2 + span_b);
    ny = FftSize(static_cast<int>(std::ceil(box_a.sizes().y() / pixel)) + 2 + span_b);
    const double over = static_cast<double>(nx) * ny / static_cast<double>(params.max_pixels);
    if (over <= 1) break;
    if (attempt >= 64) return yaws;  // unreachable for maps within VoxelGrid's key range
    pixel *= std::max(1.05, std::sqrt(over));
  }
  if (stats != nullptr) stats->pixel_m = pixel;

  const Eigen::Vector2d origin_a = box_a.min() - Eigen::Vector2d::Constant(pixel);
  RealFft fft({nx, ny});
  LargeVector<Complex> structure_a, dilated_a, data_a;
  double structures_a = 0;
  {
    ColumnImage image(nx, ny, pixel);
    image.Rasterise(points_a, 0.0, origin_a, params);
    Transform(fft, image.structure(), &structure_a);
    Transform(fft, image.Dilated(image.structure(), 1), &dilated_a);
    Transform(fft, image.Dilated(image.data(), kDataRadius), &data_a);
    structures_a = image.structures();
  }
  if (structures_a == 0) return yaws;
  const Eigen::Vector2d origin_b = -Eigen::Vector2d::Constant(radius_b + pixel);
  std::atomic<int> scored{0};
  const int columns_a = static_cast<int>(std::ceil(box_a.sizes().x() / pixel)) + 2;
  const int rows_a = static_cast<int>(std::ceil(box_a.sizes().y() / pixel)) + 2;
  // One per thread: b's image, its transforms and the scratch of a score.
  struct Workspace {
    Workspace(int nx_, int ny_, double pixel_m) : fft({nx_, ny_}), image_b(nx_, ny_, pixel_m) {
      weight.resize(fft.real_size());
    }
    RealFft fft;
    ColumnImage image_b;
    LargeVector<Complex> structure_b, data_b;
    LargeVector<float> weight;
  };
  // The best normalised correlation over all shifts (as in
  // SearchTranslations: hits / sqrt(b's structure in a's data * a's in b's)),
  // and the shift that gives it as the translation t of
  // x_a' = Rz(yaw) R_b x_b + t (NaN when b has no structure column).
  struct Scored {
    double score = 0;
    Eigen::Vector2d t_m = Eigen::Vector2d::Constant(std::nan(""));
  };
  const auto score = [&](double yaw, Workspace& w) {
    ++scored;
    Scored out;
    RealFft& fft_b = w.fft;
    LargeVector<float>& weight = w.weight;
    w.image_b.Rasterise(points_b, yaw, origin_b, params);
    if (w.image_b.structures() == 0) return out;
    Transform(fft_b, w.image_b.structure(), &w.structure_b);
    Transform(fft_b, w.image_b.Dilated(w.image_b.data(), kDataRadius), &w.data_b);
    const double min_pixels = std::max(1.0, params.min_overlap_fraction *
                                                std::min(structures_a, w.image_b.structures())) *
                              static_cast<double>(fft_b.real_size());
    const float* a_in_b = Correlate(fft_b, structure_a, w.data_b);
    std::copy(a_in_b, a_in_b + fft_b.real_size(), weight.begin());
    const float* b_in_a = Correlate(fft_b, data_a, w.structure_b);
    for (std::size_t i = 0; i < weight.size(); ++i) {
      const double in_a = b_in_a[i], in_b = weight[i];
      weight[i] = std::min(in_a, in_b) >= min_pixels
                      ? static_cast<float>(1.0 / std::sqrt(in_a * in_b))
                      : 0.0F;
    }
    const float* hits = Correlate(fft_b, dilated_a, w.structure_b);
    std::size_t best_i = 0;
    for (std::size_t i = 0; i < weight.size(); ++i) {
      const auto value = static_cast<double>(hits[i] * weight[i]);
      if (value > out.score) out.score = value, best_i = i;
    }
    // b's pixel j lands on a's pixel j + shift. Circular shifts: a's content
    // is [0, columns_a) x [0, rows_a), so the shifts where the images meet
    // are below those or negative.
    const int ix = static_cast<int>(best_i / static_cast<std::size_t>(ny));
    const int iy = static_cast<int>(best_i % static_cast<std::size_t>(ny));
    const Eigen::Vector2d shift(ix < columns_a ? ix : ix - nx, iy < rows_a ? iy : iy - ny);
    // b's points were turned about its levelled centroid.
    out.t_m = origin_a - origin_b + pixel * shift -
              Eigen::Rotation2Dd(yaw) * Eigen::Vector2d(centroid_b.x(), centroid_b.y());
    return out;
  };

  // Every candidate's window: a coarse pass, then the degrees around its
  // best. Each pass scores all its (candidate, offset) pairs in parallel;
  // the best of a window is then taken in the order a single thread would
  // try them (the candidate, then the coarse offsets ascending, then the
  // degrees nearest first), the first of equal scores winning, so the result
  // does not depend on the thread count.
  const int steps = static_cast<int>(std::floor(params.window_deg / params.coarse_step_deg));
  struct Trial {
    std::size_t candidate;
    double offset_deg;
    Scored scored;
  };
  std::vector<std::unique_ptr<Workspace>> workspaces(
      static_cast<std::size_t>(std::max(1, threads)));
  const auto score_all = [&](std::vector<Trial>* trials) {
    ParallelFor(trials->size(), threads, [&](std::size_t t, std::size_t worker) {
      if (!workspaces[worker]) workspaces[worker] = std::make_unique<Workspace>(nx, ny, pixel);
      Trial& trial = (*trials)[t];
      trial.scored =
          score(yaws[trial.candidate] + trial.offset_deg * kRadPerDeg, *workspaces[worker]);
    });
  };
  struct Window {
    double candidate_score = 0, best_offset = 0;
    Scored best;
  };
  std::vector<Window> windows(yaws.size());
  const auto take_best = [&](const std::vector<Trial>& trials) {
    for (const Trial& trial : trials) {
      Window& window = windows[trial.candidate];
      if (trial.scored.score > window.best.score) {
        window.best_offset = trial.offset_deg;
        window.best = trial.scored;
      }
    }
  };
  std::vector<Trial> coarse;
  for (std::size_t c = 0; c < yaws.size(); ++c) {
    coarse.push_back({c, 0.0, {}});
    for (int k = -steps; k <= steps; ++k) {
      if (k != 0) coarse.push_back({c, k * params.coarse_step_deg, {}});
    }
  }
  score_all(&coarse);
  for (const Trial& trial : coarse) {
    if (trial.offset_deg != 0.0) continue;
    windows[trial.candidate].best = trial.scored;
    windows[trial.candidate].candidate_score = trial.scored.score;
  }
  take_best(coarse);
  std::vector<Trial> fine;
  for (std::size_t c = 0; c < yaws.size(); ++c) {
    const double coarse_best = windows[c].best_offset;
    for (double d = 1; d < params.coarse_step_deg; ++d) {
      for (double offset : {coarse_best - d, coarse_best + d}) {
        if (std::abs(offset) <= params.window_deg) fine.push_back({c, offset, {}});
      }
    }
  }
  score_all(&fine);
  take_best(fine);
  std::vector<std::pair<double, double>> refined;  // (2D score, yaw)
  std::vector<double> candidate_scores, window_scores, window_yaws;
  std::vector<Eigen::Vector2d> window_shifts;
  for (std::size_t c = 0; c < yaws.size(); ++c) {
    const Window& window = windows[c];
    const double yaw = yaws[c];
    candidate_scores.push_back(window.candidate_score);
    window_scores.push_back(window.best.score);
    window_yaws.push_back(yaw + window.best_offset * kRadPerDeg);
    window_shifts.push_back(window.best.t_m);
    if (std::abs(window.best_offset) >= params.min_change_deg) {
      refined.emplace_back(window.best.score,
                           std::remainder(yaw + window.best_offset * kRadPerDeg, 2 * M_PI));
    }
  }
  std::stable_sort(refined.begin(), refined.end(),
                   [](const auto& x, const auto& y) { return x.first > y.first; });
  if (static_cast<int>(refined.size()) > params.max_added) {
    refined.resize(static_cast<std::size_t>(params.max_added));
  }
  if (stats != nullptr) {
    stats->yaws_scored = scored.load();
    stats->yaws_added = static_cast<int>(refined.size());
    stats->candidate_scores = candidate_scores;
    stats->window_scores = window_scores;
    stats->window_yaws = window_yaws;
    stats->window_shifts_m = window_shifts;
  }
  std::vector<double> out = yaws;
  for (const auto& scored_yaw : refined) out.push_back(scored_yaw.second);
  return out;
}

std::vector<double> PlanViewHeights(const VoxelGrid& a, const Eigen::Matrix3d& R_a,
                                    const VoxelGrid& b, const Eigen::Matrix3d& R_b,
                                    const std::vector<double>& yaws,
                                    const std::vector<Eigen::Vector2d>& t_m, double pixel_m,
                                    int threads) {
  std::vector<double> heights(yaws.size(), std::nan(""));
  if (!(pixel_m > 0) || a.empty() || b.empty()) return heights;
  // Column (ix, iy) as one key: both indices to 32 bits, no shift of a
  // negative number.
  const auto column = [&](const Eigen::Vector3d& p) {
    const auto ix = static_cast<std::uint32_t>(
        static_cast<std::int32_t>(std::clamp(std::floor(p.x() / pixel_m), -2e9, 2e9)));
    const auto iy = static_cast<std::uint32_t>(
        static_cast<std::int32_t>(std::clamp(std::floor(p.y() / pixel_m), -2e9, 2e9)));
    return (static_cast<std::uint64_t>(ix) << 32) | iy;
  };
  // (column, lowest height) of a map, sorted by column.
  using Lowest = std::vector<std::pair<std::uint64_t, double>>;
  const auto lowest_of = [&](Lowest* points) {
    std::sort(points->begin(), points->end());  // lowest first within a column
    points->erase(std::unique(points->begin(), points->end(),
                              [](const auto& x, const auto& y) { return x.first == y.first; }),
                  points->end());
  };
  Lowest lowest_a;
  lowest_a.reserve(a.num_occupied());
  for (const Eigen::Vector3d& c : a.occupied_centres()) {
    const Eigen::Vector3d p = R_a * c;
    lowest_a.emplace_back(column(p), p.z());
  }
  lowest_of(&lowest_a);
  // One placement per index, on every thread: each sorts b's 150k columns
  // of a campus crop (~10 ms), and a plan view tries several.
  const std::size_t placements = std::min(yaws.size(), t_m.size());
  ParallelFor(placements, threads, [&](std::size_t k, std::size_t) {
    if (!std::isfinite(yaws[k]) || !t_m[k].allFinite()) return;
    const Eigen::Matrix3d R =
        Eigen::AngleAxisd(yaws[k], Eigen::Vector3d::UnitZ()).toRotationMatrix() * R_b;
    Lowest lowest_b;
    lowest_b.reserve(b.num_occupied());
    for (const Eigen::Vector3d& c : b.occupied_centres()) {
      Eigen::Vector3d p = R * c;
      p.head<2>() += t_m[k];
      lowest_b.emplace_back(column(p), p.z());
    }
    lowest_of(&lowest_b);
    std::vector<double> dz;
    auto in_a = lowest_a.begin();
    for (const auto& [key, z] : lowest_b) {
      in_a = std::lower_bound(in_a, lowest_a.end(), key,
                              [](const auto& x, std::uint64_t k_) { return x.first < k_; });
      if (in_a == lowest_a.end()) break;
      if (in_a->first == key) dz.push_back(in_a->second - z);
    }
    if (dz.empty()) return;
    const auto middle = dz.begin() + static_cast<std::ptrdiff_t>(dz.size() / 2);
    std::nth_element(dz.begin(), middle, dz.end());
    heights[k] = *middle;
  });
  return heights;
}

}  // namespace mapd::voxel
