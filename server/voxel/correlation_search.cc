#include "voxel/correlation_search.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <complex>
#include <cstdint>
#include <string>
#include <utility>

#include "voxel/fft_support.h"
#include "voxel/large_array.h"
#include "voxel/parallel.h"

namespace mapd::voxel {
namespace {

// A point sample of a map: an occupied voxel centre (occupied = true) or a
// piece of a free cube (free_volume = its volume, in coarse cells). 32 bytes:
// a crop of 5 cm voxels has over a million free pieces.
struct Sample {
  Eigen::Vector3d p;
  float free_volume = 0.0F;
  bool occupied = false;
};

// The occupied centres and the free cubes cut into pieces of about half a
// coarse cell (rounded to whole voxels), so that a rotated cube spreads over
// the right cells. Rounded, not floored: at 3 voxels a cell, floor made every
// free voxel a sample (1.2M per yaw on fr_078_tidyup crops); pieces of 2
// voxels changed no outcome of the benchmark's 108 pairs and took 8 % off
// fr_078_tidyup merges (docs/archive/voxel-merge-history.md, "Exact speed-ups and free
// pieces of two voxels").
LargeVector<Sample> Samples(const VoxelGrid& grid, double cell_m, int threads) {
  const double res = grid.resolution();
  const int piece = std::max(1, static_cast<int>(std::lround(0.5 * cell_m / res)));
  const double cell_volume = std::pow(cell_m / res, 3);
  // Counted first: growing the vector cost a tenth of the search on
  // fr_078_tidyup (copies and page faults).
  std::size_t count = grid.num_occupied();
  grid.ForEachFreeCube([&](const VoxelKey&, int edge) {
    const std::size_t per_edge = static_cast<std::size_t>((edge + piece - 1) / piece);
    count += per_edge * per_edge * per_edge;
  });
  // Sized on every thread first (a fresh block's page zeroing shared), then
  // filled in order on this one.
  LargeVector<Sample> samples;
  ResizeInParallel(&samples, count, threads);
  std::size_t k = 0;
  const auto add = [&](const Sample& sample) {
    if (k < samples.size()) {
      samples[k] = sample;
    } else {
      samples.push_back(sample);  // never, while the count above is the fill below
    }
    ++k;
  };
  for (const Eigen::Vector3d& c : grid.occupied_centres()) add({c, 0.0F, true});
  grid.ForEachFreeCube([&](const VoxelKey& min_key, int edge) {
    const int step = std::min(edge, piece);
    const auto volume = static_cast<float>(std::pow(step, 3) / cell_volume);
    for (int x = 0; x < edge; x += step) {
      for (int y = 0; y < edge; y += step) {
        for (int z = 0; z < edge; z += step) {
          const Eigen::Vector3d corner = (min_key + VoxelKey(x, y, z)).cast<double>() * res;
          add({corner + Eigen::Vector3d::Constant(0.5 * step * res), volume, false});
        }
      }
    }
  });
  samples.resize(k);
  return samples;
}

struct CellBox {
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(1e300);
  Eigen::Vector3d hi = Eigen::Vector3d::Constant(-1e300);
};

// Occupancy (0/1) and free share (0..1, 0 where occupied) on a padded grid.
class CoarseGrid {
 public:
  CoarseGrid(const std::array<int, 3>& n, const Eigen::Vector3d& origin, double cell)
      : n_(n), occ_lo_(n), occ_hi_{-1, -1, -1}, origin_(origin), cell_(cell) {
    const std::size_t size = static_cast<std::size_t>(n[0]) * n[1] * n[2];
    // Zeros never written: a map's content fills a fifth of the padded
    // grid or less, and only those pages are touched.
    occ_ = ZeroedLargeArray<std::uint8_t>(size);
    free_ = ZeroedLargeArray<float>(size);
    dilated_ = ZeroedLargeArray<std::uint8_t>(size);
    cover_ = ZeroedLargeArray<std::uint8_t>(size);
    pass_ = ZeroedLargeArray<std::uint8_t>(size);
  }
  // Empties the grid and moves it to `origin`; keeps its buffers (every yaw
  // of b reuses one grid: fresh 16M-cell buffers cost page faults). Every
  // buffer is zero outside the content rows, so only those are cleared.
  void Reset(const Eigen::Vector3d& origin) {
    origin_ = origin;
    ForEachContentRow([&](std::size_t row) {
      for (auto* v : {&occ_, &dilated_, &cover_, &pass_}) std::fill_n(v->begin() + row, n_[2], 0);
      std::fill_n(free_.begin() + row, n_[2], 0.0F);
    });
    occ_lo_ = n_;
    occ_hi_ = {-1, -1, -1};
    free_hi_ = {-1, -1};
    extent_ = {0, 0};
  }
  void Add(const Eigen::Vector3d& p, const Sample& s) {
    const Eigen::Vector3d f = (p - origin_) / cell_;
    const int x = static_cast<int>(std::floor(f.x()));
    const int y = static_cast<int>(std::floor(f.y()));
    const int z = static_cast<int>(std::floor(f.z()));
    if (x < 0 || y < 0 || z < 0 || x >= n_[0] || y >= n_[1] || z >= n_[2]) return;
    const std::size_t i = (static_cast<std::size_t>(x) * n_[1] + y) * n_[2] + z;
    if (s.occupied) {
      occ_[i] = 1;
      occ_lo_ = {std::min(occ_lo_[0], x), std::min(occ_lo_[1], y), std::min(occ_lo_[2], z)};
      occ_hi_ = {std::max(occ_hi_[0], x), std::max(occ_hi_[1], y), std::max(occ_hi_[2], z)};
    } else {
      free_[i] += s.free_volume;
      free_hi_ = {std::max(free_hi_[0], x), std::max(free_hi_[1], y)};
    }
  }
  // A wall rasterised in two grids offset by a fraction of a cell lands in
  // the same or a neighbouring cell: free space within one cell of an
  // occupied cell does not count (else half the true wall cells would be
  // penalised), and dilated_occ() is what the other map's walls may hit.
  void Finish(int cover_radius) {
    for (int k = 0; k < 2; ++k) {
      const int occ_end = occ_hi_[0] < 0 ? 0 : std::min(n_[k], occ_hi_[k] + cover_radius + 1);
      extent_[k] = std::max(occ_end, free_hi_[k] + 1);
    }
    Dilate(1, &dilated_);
    Dilate(cover_radius, &cover_);
    occupied_cells_ = 0;
    ForEachContentRow([&](std::size_t row) {
      for (std::size_t i = row; i < row + static_cast<std::size_t>(n_[2]); ++i) {
        free_[i] = dilated_[i] != 0 ? 0.0F : std::min(1.0F, free_[i]);
        if (free_[i] > 0) cover_[i] = 1;
        occupied_cells_ += occ_[i];
      }
    });
  }
  // After Finish: every cell outside x < extent[0], y < extent[1] is zero
  // in every buffer (for RealFft::ForwardInBox).
  const std::array<int, 2>& extent() const { return extent_; }
  std::size_t occupied_cells() const { return occupied_cells_; }
  const ZeroedLargeArray<std::uint8_t>& occ() const { return occ_; }
  const ZeroedLargeArray<std::uint8_t>& dilated_occ() const { return dilated_; }
  // Where this map has data: within cover_radius cells of an occupied cell,
  // or free.
  const ZeroedLargeArray<std::uint8_t>& cover() const { return cover_; }
  const ZeroedLargeArray<float>& free() const { return free_; }

 private:
  // Binary dilation of occ_ (1 where an occupied cell lies within `radius`
  // cells along each axis: a cube), one axis at a time, inside the occupied
  // cells' box grown by `radius` (a map fills an eighth of its padded grid
  // or less; outside the box nothing is set). Each pass is two sweeps along
  // the axis that remember the nearest set cell behind and ahead, so it
  // costs O(cells) whatever the radius, and the innermost loop runs over
  // contiguous memory (z) on every axis.
  void Dilate(int radius, ZeroedLargeArray<std::uint8_t>* result) {
    ZeroedLargeArray<std::uint8_t>& out = *result;  // zero outside the box below
    if (occ_hi_[0] < 0) return;                     // nothing occupied
    std::array<int, 3> lo{}, hi{};
    for (std::size_t k = 0; k < 3; ++k) {
      lo[k] = std::max(0, occ_lo_[k] - radius);
      hi[k] = std::min(n_[k] - 1, occ_hi_[k] + radius);
    }
    const auto index = [&](int x, int y, int z) {
      return (static_cast<std::size_t>(x) * n_[1] + y) * n_[2] + z;
    };
    const int wz = hi[2] - lo[2] + 1;
    std::vector<int> nearest;
    // The pass along `axis` reads `in` and sets `to` (cleared in the box).
    const auto pass = [&](std::size_t axis, const ZeroedLargeArray<std::uint8_t>& in,
                          ZeroedLargeArray<std::uint8_t>* to) {
      for (int x = lo[0]; x <= hi[0]; ++x) {
        for (int y = lo[1]; y <= hi[1]; ++y) std::fill_n(to->begin() + index(x, y, lo[2]), wz, 0);
      }
      // Lines along `axis`, walked forwards then backwards; `nearest` per
      // line: the last set cell met.
      const int a_lo = lo[axis], a_hi = hi[axis];
      const auto sweep = [&](auto&& cell_of, int lines, bool forward) {
        nearest.assign(static_cast<std::size_t>(lines),
                       forward ? a_lo - radius - 1 : a_hi + radius + 1);
        for (int k = forward ? a_lo : a_hi; forward ? k <= a_hi : k >= a_lo;
             k += forward ? 1 : -1) {
          cell_of(k, [&](std::size_t line, std::size_t i) {
            int& near = nearest[line];
            if (in[i] != 0) near = k;
            if (std::abs(k - near) <= radius) (*to)[i] = 1;
          });
        }
      };
      const int wy = hi[1] - lo[1] + 1;
      for (const bool forward : {true, false}) {
        if (axis == 0) {  // lines along x: one per (y, z) of the box
          sweep(
              [&](int x, auto&& visit) {
                for (int y = lo[1]; y <= hi[1]; ++y) {
                  const std::size_t row = index(x, y, lo[2]);
                  const std::size_t line = static_cast<std::size_t>(y - lo[1]) * wz;
                  for (int z = 0; z < wz; ++z) visit(line + z, row + z);
                }
              },
              wy * wz, forward);
        } else if (axis == 1) {  // along y: one per (x, z), x outermost
          for (int x = lo[0]; x <= hi[0]; ++x) {
            sweep(
                [&](int y, auto&& visit) {
                  const std::size_t row = index(x, y, lo[2]);
                  for (int z = 0; z < wz; ++z) visit(static_cast<std::size_t>(z), row + z);
                },
                wz, forward);
          }
        } else {  // along z: one per (x, y)
          for (int x = lo[0]; x <= hi[0]; ++x) {
            for (int y = lo[1]; y <= hi[1]; ++y) {
              sweep([&](int z, auto&& visit) { visit(0, index(x, y, z)); }, 1, forward);
            }
          }
        }
      }
    };
    pass(0, occ_, &out);
    pass(1, out, &pass_);
    pass(2, pass_, &out);
  }

  // Calls visit(index of the row's first cell) for every z row inside extent_.
  template <typename Visit>
  void ForEachContentRow(Visit&& visit) const {
    for (int x = 0; x < extent_[0]; ++x) {
      for (int y = 0; y < extent_[1]; ++y) visit((static_cast<std::size_t>(x) * n_[1] + y) * n_[2]);
    }
  }

  std::array<int, 3> n_;
  std::array<int, 3> occ_lo_, occ_hi_;  // occupied cells' box (hi < 0: none)
  std::array<int, 2> free_hi_{-1, -1};  // the free samples' last x, y (< 0: none)
  std::array<int, 2> extent_{0, 0};     // see extent()
  std::size_t occupied_cells_ = 0;
  Eigen::Vector3d origin_;
  double cell_;
  ZeroedLargeArray<std::uint8_t> occ_, dilated_, cover_;
  ZeroedLargeArray<float> free_;
  ZeroedLargeArray<std::uint8_t> pass_;  // Dilate's scratch
};

struct Peak {
  float score;
  std::array<int, 3> shift;
};

// The best `count` of the (score, cell) pairs in `*pairs` (the cells with a
// positive score, ascending) at least `separation` cells apart (circular
// distance on the padded grid). Reorders `*pairs` (a buffer every yaw reuses).
std::vector<Peak> TopPeaks(LargeVector<std::pair<float, std::size_t>>* pairs,
                           const std::array<int, 3>& n, int count, double separation) {
  auto& order = *pairs;
  const std::size_t keep = std::min<std::size_t>(order.size(), 4096);
  std::partial_sort(order.begin(), order.begin() + static_cast<std::ptrdiff_t>(keep), order.end(),
                    [](const auto& x, const auto& y) { return x.first > y.first; });
  std::vector<Peak> peaks;
  for (std::size_t k = 0; k < keep && static_cast<int>(peaks.size()) < count; ++k) {
    const std::size_t i = order[k].second;
    const std::array<int, 3> idx = {static_cast<int>(i / (static_cast<std::size_t>(n[1]) * n[2])),
                                    static_cast<int>((i / n[2]) % n[1]),
                                    static_cast<int>(i % n[2])};
    bool near = false;
    for (const Peak& p : peaks) {
      double d2 = 0;
      for (int a = 0; a < 3; ++a) {
        int d = std::abs(idx[a] - p.shift[a]);
        d = std::min(d, n[a] - d);
        d2 += static_cast<double>(d) * d;
      }
      near = near || d2 < separation * separation;
    }
    if (!near) peaks.push_back({order[k].first, idx});
  }
  return peaks;
}

// a levelled; b levelled and turned by each yaw, in the box of its occupied
// voxels (the grid holds the largest of these boxes; a cylinder about b's
// centroid, which holds any yaw, made the outdoor grids up to a third
// larger).
struct Boxes {
  CellBox a;
  std::vector<CellBox> b;    // per yaw
  Eigen::Vector3d extent_a;  // of a's box
  Eigen::Vector3d extent_b;  // the largest of b's boxes per axis
};

Boxes BoxesOf(const VoxelGrid& a, const Eigen::Matrix3d& R_a, const VoxelGrid& b,
              const Eigen::Matrix3d& R_b, const std::vector<double>& yaws) {
  Boxes boxes;
  for (const Eigen::Vector3d& c : a.occupied_centres()) {
    const Eigen::Vector3d p = R_a * c;
    boxes.a.lo = boxes.a.lo.cwiseMin(p);
    boxes.a.hi = boxes.a.hi.cwiseMax(p);
  }
  boxes.b.resize(yaws.size());
  boxes.extent_b = Eigen::Vector3d::Zero();
  for (std::size_t k = 0; k < yaws.size(); ++k) {
    const Eigen::Matrix3d R =
        Eigen::AngleAxisd(yaws[k], Eigen::Vector3d::UnitZ()).toRotationMatrix() * R_b;
    for (const Eigen::Vector3d& c : b.occupied_centres()) {
      const Eigen::Vector3d p = R * c;
      boxes.b[k].lo = boxes.b[k].lo.cwiseMin(p);
      boxes.b[k].hi = boxes.b[k].hi.cwiseMax(p);
    }
    boxes.extent_b = boxes.extent_b.cwiseMax(boxes.b[k].hi - boxes.b[k].lo);
  }
  boxes.extent_a = boxes.a.hi - boxes.a.lo;
  return boxes;
}

// The padded grid for cells of `cell` metres: a's cells, b's, and the FFT
// size of every shift where they meet, per axis.
struct GridDims {
  std::array<int, 3> na{}, nb{}, n{};
  std::size_t cells() const {
    return static_cast<std::size_t>(n[0]) * static_cast<std::size_t>(n[1]) *
           static_cast<std::size_t>(n[2]);
  }
};

GridDims DimsOf(const Boxes& boxes, double cell) {
  GridDims d;
  for (std::size_t k = 0; k < 3; ++k) {
    const auto axis = static_cast<Eigen::Index>(k);
    d.na[k] = static_cast<int>(std::ceil(boxes.extent_a[axis] / cell)) + 2;
    d.nb[k] = static_cast<int>(std::ceil(boxes.extent_b[axis] / cell)) + 2;
    d.n[k] = FftSize(d.na[k] + d.nb[k]);
  }
  return d;
}

}  // namespace

std::size_t CorrelationGridCells(const VoxelGrid& a, const Eigen::Matrix3d& R_a, const VoxelGrid& b,
                                 const Eigen::Matrix3d& R_b, const std::vector<double>& yaws,
                                 double finest_resolution_m, const CorrelationParams& params) {
  if (a.empty() || b.empty() || yaws.empty() || !(finest_resolution_m > 0)) return 0;
  return DimsOf(BoxesOf(a, R_a, b, R_b, yaws), params.cell_voxels * finest_resolution_m).cells();
}

Status CorrelationParams::Validate() const {
  if (after_corner_stages < 0 || after_corner_stages > 100) {
    return Status::InvalidArgument("correlation.after_corner_stages must be in [0, 100]");
  }
  if (!(cell_voxels >= 1 && cell_voxels <= 64)) {
    return Status::InvalidArgument("correlation.cell_voxels must be in [1, 64]");
  }
  if (max_cells < 1000 || max_cells > 200'000'000) {
    return Status::InvalidArgument("correlation.max_cells must be in [1000, 200000000]");
  }
  if (!(free_weight >= 0 && free_weight <= 100)) {
    return Status::InvalidArgument("correlation.free_weight must be in [0, 100]");
  }
  if (peaks_per_yaw < 1 || max_hypotheses < 1 || max_hypotheses > 1000) {
    return Status::InvalidArgument(
        "correlation.peaks_per_yaw must be >= 1 and max_hypotheses in [1, 1000]");
  }
  if (!(coverage_radius_m > 0 && coverage_radius_m <= 100) ||
      !(min_overlap_fraction >= 0 && min_overlap_fraction <= 1)) {
    return Status::InvalidArgument(
        "correlation.coverage_radius_m must be in (0, 100] and min_overlap_fraction in [0, 1]");
  }
  if (!(min_peak_separation_cells >= 0 && min_peak_separation_cells <= 1000)) {
    return Status::InvalidArgument("correlation.min_peak_separation_cells must be in [0, 1000]");
  }
  return yaw_refinement.Validate();
}

StatusOr<std::vector<CorrelationHypothesis>> SearchTranslations(
    const VoxelGrid& a, const Eigen::Matrix3d& R_a, const VoxelGrid& b, const Eigen::Matrix3d& R_b,
    const std::vector<double>& yaws, double finest_resolution_m, const CorrelationParams& params,
    CorrelationStats* stats, int threads) {
  MAPD_RETURN_IF_ERROR(params.Validate());
  if (!(finest_resolution_m > 0)) return Status::InvalidArgument("resolution must be > 0");
  if (a.empty() || b.empty() || yaws.empty()) return std::vector<CorrelationHypothesis>{};

  const Boxes boxes = BoxesOf(a, R_a, b, R_b, yaws);
  const CellBox& box_a = boxes.a;
  const std::vector<CellBox>& boxes_b = boxes.b;
  double cell = params.cell_voxels * finest_resolution_m;
  GridDims dims = DimsOf(boxes, cell);
  for (int attempt = 0; dims.cells() > params.max_cells; ++attempt) {
    if (attempt >= 64) {
      return Status::ResourceExhausted("correlation grid above max_cells = " +
                                       std::to_string(params.max_cells));
    }
    cell *= std::max(1.05, std::cbrt(static_cast<double>(dims.cells()) / params.max_cells));
    dims = DimsOf(boxes, cell);
  }
  const std::array<int, 3>& na = dims.na;
  const std::array<int, 3>& n = dims.n;
  if (stats != nullptr) {
    stats->yaws = static_cast<int>(yaws.size());
    stats->cell_m = cell;
    stats->grid_cells = static_cast<std::size_t>(n[0]) * n[1] * n[2];
  }

  const Eigen::Vector3d origin_a = box_a.lo - Eigen::Vector3d::Constant(cell);
  const int cover_radius =
      std::max(1, static_cast<int>(std::lround(params.coverage_radius_m / cell)));
  const auto w = static_cast<float>(params.free_weight);
  const std::size_t n1 = static_cast<std::size_t>(n[1]), n2 = static_cast<std::size_t>(n[2]);
  // a's content rows (CoarseGrid::extent) as its three transform inputs,
  // each row of n2 values: a's spectra are made again for every FFT size.
  LargeVector<float> occ_rows_a, hit_rows_a, cover_rows_a;  // hit: dilated occupancy - w * free
  double cells_a = 0;
  std::array<int, 2> rows_a{};
  // One grid for both maps: b's yaws reuse a's buffers (Reset clears only
  // the content rows), so the search maps 16M-cell buffers once, not twice.
  CoarseGrid grid(n, origin_a, cell);
  {
    for (const Sample& s : Samples(a, cell, threads)) grid.Add(R_a * s.p, s);
    grid.Finish(cover_radius);
    const auto& occ = grid.occ();
    const auto& dilated = grid.dilated_occ();
    const auto& free = grid.free();
    const auto& cover = grid.cover();
    rows_a = grid.extent();
    const std::size_t cells = static_cast<std::size_t>(rows_a[0]) * rows_a[1] * n2;
    for (auto* rows : {&occ_rows_a, &hit_rows_a, &cover_rows_a})
      ResizeInParallel(rows, cells, threads);
    const std::size_t row_cells = static_cast<std::size_t>(rows_a[1]) * n2;
    ParallelFor(static_cast<std::size_t>(rows_a[0]), threads, [&](std::size_t x, std::size_t) {
      std::size_t k = x * row_cells;
      for (std::size_t y = 0; y < static_cast<std::size_t>(rows_a[1]); ++y) {
        for (std::size_t i = (x * n1 + y) * n2, end = i + n2; i < end; ++i, ++k) {
          occ_rows_a[k] = occ[i];
          hit_rows_a[k] = dilated[i] - w * free[i];
          cover_rows_a[k] = cover[i];
        }
      }
    });
    cells_a = static_cast<double>(grid.occupied_cells());
  }
  const LargeVector<Sample> samples_b = Samples(b, cell, threads);

  std::vector<CorrelationHypothesis> out;
  // The FFT, reshaped to each yaw's size on the common grid's buffers, a's
  // three spectra on the current size, and b's buffers. Reserved for the
  // common grid (untouched until used), so no size change maps fresh pages.
  RealFft fft({n[0], n[1], n[2]}, threads);
  std::array<int, 3> size{};  // of the spectra below; none yet
  LargeVector<Complex> occ_a, hit_a, cover_a, occ_b;
  for (auto* v : {&occ_a, &hit_a, &cover_a, &occ_b}) v->reserve(fft.complex_size());
  // 1 / normaliser, 0 where no peak may be; read and written only at the
  // shifts where the grids meet (for_each_cell below), so never cleared.
  ZeroedLargeArray<float> weight(fft.real_size());
  LargeVector<std::pair<float, std::size_t>> positive;  // (score, cell), ascending cells
  for (std::size_t y = 0; y < yaws.size(); ++y) {
    const double yaw = yaws[y];
    const Eigen::Matrix3d R =
        Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix() * R_b;
    // b's grid origin: its turned box, one cell of margin.
    const Eigen::Vector3d origin = boxes_b[y].lo - Eigen::Vector3d::Constant(cell);
    grid.Reset(origin);
    for (const Sample& s : samples_b) grid.Add(R * s.p, s);
    grid.Finish(cover_radius);
    const auto& occ = grid.occ();
    const auto& free = grid.free();
    const auto& cover = grid.cover();
    const double cells_b = static_cast<double>(grid.occupied_cells());
    const std::array<int, 2>& extent = grid.extent();
    // This yaw's FFT size: along x and y a's content rows plus b's, every
    // shift where they meet without wrapping around (n holds b's largest box
    // over the yaws: a slab turned by 90 deg is long in x or in y, not both,
    // so a yaw's grid is smaller: by 28-60 % on the campus crops, 17-38 % on
    // fr_078_tidyup's). Where they do not fit in n, n, as before: the same
    // correlation either way, rounding aside.
    std::array<int, 3> m = n;
    for (std::size_t k = 0; k < 2; ++k) {
      const int shifts = rows_a[k] + extent[k] - 1;
      if (shifts <= n[k]) m[k] = FftSize(std::max(shifts, 1));
    }
    if (m != size) {
      size = m;
      fft.Reshape({m[0], m[1], m[2]});
      const auto spectrum_of = [&](const LargeVector<float>& rows, LargeVector<Complex>* spectra) {
        const Complex* spectrum = fft.ForwardInBoxRows(rows_a, [&](int x, int y_, float* row) {
          const float* from = rows.data() + (static_cast<std::size_t>(x) * rows_a[1] + y_) * n2;
          std::copy(from, from + n2, row);
        });
        AssignInParallel(spectra, spectrum, fft.complex_size(), threads);
      };
      spectrum_of(occ_rows_a, &occ_a);
      spectrum_of(hit_rows_a, &hit_a);
      spectrum_of(cover_rows_a, &cover_a);
    }
    const std::size_t spectrum_size = fft.complex_size();
    // b's rows, copied from the grid (laid out for n) into the transform's.
    const auto rows_of = [&](const auto& field) {
      return [&](int x, int y_, float* row) {
        const std::size_t from = (static_cast<std::size_t>(x) * n1 + y_) * n2;
        for (std::size_t z = 0; z < n2; ++z) row[z] = static_cast<float>(field[from + z]);
      };
    };
    const Complex* spectrum = fft.ForwardInBoxRows(extent, rows_of(occ));
    AssignInParallel(&occ_b, spectrum, spectrum_size, threads);
    // The score is normalised by the occupied cells each map has where the
    // other has data: sliding a corridor over more of the other map adds
    // hits but adds as many cells that miss. Overlaps below
    // min_overlap_fraction of the smaller map are no peak (a few cells can
    // agree by chance).
    const double min_cells = std::max(params.min_overlap_fraction * std::min(cells_a, cells_b) *
                                          static_cast<double>(fft.real_size()),
                                      1.0);
    Complex* product = fft.ForwardInBoxRows(extent, rows_of(cover));
    // Element-wise products on every thread (ParallelRanges).
    const auto products = [&](auto&& at) {
      ParallelRanges(spectrum_size, threads, [&](std::size_t begin, std::size_t end) {
        for (std::size_t i = begin; i < end; ++i) at(i);
      });
    };
    products([&](std::size_t i) { product[i] = MulConj(occ_a[i], product[i]); });
    // Only shifts where the two grids' content can meet can score: a's
    // content rows [0, rows_a) against b's [0, extent) are shifts
    // [0, rows_a) and [n - extent + 1, n) along x and y; the inverses and
    // every loop below skip the other rows.
    RealFft::Ranges meet[2];
    for (std::size_t k = 0; k < 2; ++k) {
      const int first_end = std::min(rows_a[k], m[k]);
      const int second_begin = std::max(first_end, m[k] - extent[k] + 1);
      if (first_end > 0) meet[k].push_back({0, first_end});
      if (second_begin < m[k]) meet[k].push_back({second_begin, m[k]});
    }
    const auto for_each_cell = [&](auto&& visit) {  // of the rows that meet, ascending
      for (const auto& [x0, x1] : meet[0]) {
        for (int x = x0; x < x1; ++x) {
          for (const auto& [y0, y1] : meet[1]) {
            const std::size_t begin = (static_cast<std::size_t>(x) * m[1] + y0) * m[2];
            const std::size_t end = begin + static_cast<std::size_t>(y1 - y0) * m[2];
            for (std::size_t i = begin; i < end; ++i) visit(i);
          }
        }
      }
    };
    const float* a_in_b = fft.InverseRows(meet[0], meet[1]);
    for_each_cell([&](std::size_t i) { weight[i] = a_in_b[i]; });
    product = fft.spectrum();
    products([&](std::size_t i) { product[i] = MulConj(cover_a[i], occ_b[i]); });
    const float* b_in_a = fft.InverseRows(meet[0], meet[1]);
    for_each_cell([&](std::size_t i) {
      const double in_a = b_in_a[i], in_b = weight[i];
      weight[i] =
          std::min(in_a, in_b) >= min_cells ? static_cast<float>(1.0 / std::sqrt(in_a * in_b)) : 0;
    });
    product = fft.ForwardInBoxRows(extent, rows_of(free));
    products([&](std::size_t i) {
      product[i] = MulConj(hit_a[i], occ_b[i]) - MulConj(w * occ_a[i], product[i]);
    });
    float* score = fft.InverseRows(meet[0], meet[1]);
    positive.clear();
    for_each_cell([&](std::size_t i) {
      score[i] *= weight[i];
      if (score[i] > 0) positive.emplace_back(score[i], i);
    });
    for (const Peak& peak :
         TopPeaks(&positive, m, params.peaks_per_yaw, params.min_peak_separation_cells)) {
      Eigen::Vector3d shift;
      for (int k = 0; k < 3; ++k) {
        const int s = peak.shift[static_cast<std::size_t>(k)];
        shift[k] = s < na[static_cast<std::size_t>(k)] ? s : s - m[static_cast<std::size_t>(k)];
      }
      // b's cell j lands on a's cell j + shift: x_a' = R x_b + t.
      const Eigen::Vector3d t = origin_a - origin + shift * cell;
      CorrelationHypothesis h;
      h.yaw_rad = yaw;
      h.score = peak.score;
      h.T_a_b.linear() = R_a.transpose() * R;
      h.T_a_b.translation() = R_a.transpose() * t;
      out.push_back(h);
    }
  }
  std::stable_sort(out.begin(), out.end(),
                   [](const auto& x, const auto& y) { return x.score > y.score; });
  if (static_cast<int>(out.size()) > params.max_hypotheses) {
    out.resize(static_cast<std::size_t>(params.max_hypotheses));
  }
  return out;
}

}  // namespace mapd::voxel
