#include "voxel/nearest_voxel.h"

#include <algorithm>
#include <cmath>

namespace mapd::voxel {
namespace {

std::uint64_t PackCell(const Eigen::Vector3i& c) {
  return (static_cast<std::uint64_t>(static_cast<std::uint32_t>(c.x()) & 0x1FFFFF) << 42) |
         (static_cast<std::uint64_t>(static_cast<std::uint32_t>(c.y()) & 0x1FFFFF) << 21) |
         (static_cast<std::uint64_t>(static_cast<std::uint32_t>(c.z()) & 0x1FFFFF));
}

// out |= in moved by `shift` bits towards higher (up) or lower indices.
void OrShifted(const std::vector<std::uint64_t>& in, std::size_t shift, bool up,
               std::vector<std::uint64_t>* out) {
  const std::size_t words = in.size();
  const std::size_t w = shift >> 6;
  const unsigned b = static_cast<unsigned>(shift & 63);
  if (w >= words) return;
  for (std::size_t i = 0; i + w < words; ++i) {
    // up: bit j of in goes to j + shift; down: to j - shift.
    const std::size_t to = up ? i + w : i;
    const std::size_t from = up ? i : i + w;
    std::uint64_t v = b == 0 ? in[from] : (up ? in[from] << b : in[from] >> b);
    (*out)[to] |= v;
    if (b != 0) {
      if (up && to + 1 < words) (*out)[to + 1] |= in[from] >> (64 - b);
      if (!up && from + 1 < words) (*out)[to] |= in[from + 1] << (64 - b);
    }
  }
}

}  // namespace

NearestVoxelIndex::NearestVoxelIndex(const std::vector<Eigen::Vector3d>& points, double cell_m)
    : cell_m_(cell_m) {
  std::vector<Eigen::Vector3i> cells;
  cells.reserve(points.size());
  for (const Eigen::Vector3d& p : points) cells.push_back(Cell(p));
  if (cells.empty()) return;
  Eigen::Vector3i lo = cells.front(), hi = cells.front();
  for (const auto& c : cells) {
    lo = lo.cwiseMin(c);
    hi = hi.cwiseMax(c);
  }
  // (cell key, point index), sorted: by bit index when dense, else by packed key.
  std::vector<std::pair<std::uint64_t, int>> keyed;
  keyed.reserve(points.size());
  const bool dense = occupied_.Reset(lo, hi - lo + Eigen::Vector3i::Ones(), kMaxBits);
  for (std::size_t i = 0; i < cells.size(); ++i) {
    const std::uint64_t key = dense ? occupied_.Index(cells[i] - lo) : PackCell(cells[i]);
    keyed.push_back({key, static_cast<int>(i)});
  }
  std::sort(keyed.begin(), keyed.end());
  sorted_.reserve(keyed.size());
  order_.reserve(keyed.size());
  for (std::size_t i = 0; i < keyed.size(); ++i) {
    const bool new_cell = i == 0 || keyed[i].first != keyed[i - 1].first;
    if (dense && new_cell) {
      occupied_.words[keyed[i].first >> 6] |= std::uint64_t{1} << (keyed[i].first & 63);
      first_.push_back(static_cast<int>(i));
    } else if (!dense) {
      if (new_cell) cells_[keyed[i].first] = {static_cast<int>(i), 0};
      ++cells_[keyed[i].first].second;
    }
    sorted_.push_back(points[static_cast<std::size_t>(keyed[i].second)]);
    order_.push_back(keyed[i].second);
  }
  if (!dense) return;
  first_.push_back(static_cast<int>(keyed.size()));
  rank_.resize(occupied_.words.size() + 1, 0);
  for (std::size_t w = 0; w < occupied_.words.size(); ++w) {
    rank_[w + 1] = rank_[w] + static_cast<std::uint32_t>(__builtin_popcountll(occupied_.words[w]));
  }
  MarkNear(cells);
}

// near_: over the box grown by kReachCells, one bit per cell that may have a
// point within kReachCells cells along every axis (a cube). Built by OR-ing
// the occupied bits shifted by every offset of the cube, one axis at a time.
// A shift along x also carries bits from the end of one row into the next,
// and so on: extra bits only, which cost a scan and change no answer.
void NearestVoxelIndex::MarkNear(const std::vector<Eigen::Vector3i>& cells) {
  const Eigen::Vector3i margin = Eigen::Vector3i::Constant(kReachCells);
  if (!near_.Reset(occupied_.lo - margin, occupied_.size + 2 * margin, kMaxBits)) return;
  for (const auto& c : cells) near_.Set(c);
  const Eigen::Vector3i& size = near_.size;
  const std::size_t strides[3] = {1, static_cast<std::size_t>(size.x()),
                                  static_cast<std::size_t>(size.x()) * size.y()};
  for (const std::size_t stride : strides) {
    std::vector<std::uint64_t> grown = near_.words;
    for (int k = 1; k <= kReachCells; ++k) {
      OrShifted(near_.words, k * stride, /*up=*/true, &grown);
      OrShifted(near_.words, k * stride, /*up=*/false, &grown);
    }
    near_.words.swap(grown);
  }
}

Eigen::Vector3i NearestVoxelIndex::Cell(const Eigen::Vector3d& p) const {
  const Eigen::Vector3d s = (p / cell_m_).array().floor().cwiseMax(-1e6).cwiseMin(1e6);
  return s.cast<int>();
}

[[gnu::always_inline]] inline void NearestVoxelIndex::OfferCell(std::size_t i,
                                                                const Eigen::Vector3d& q,
                                                                Best* best) const {
  const std::uint64_t below = (std::uint64_t{1} << (i & 63)) - 1;
  const std::size_t k = rank_[i >> 6] + static_cast<std::size_t>(
                                            __builtin_popcountll(occupied_.words[i >> 6] & below));
  OfferPoints(first_[k], first_[k + 1], q, best);
}

[[gnu::always_inline]] inline void NearestVoxelIndex::OfferPoints(int begin, int end,
                                                                  const Eigen::Vector3d& q,
                                                                  Best* best) const {
  for (int j = begin; j < end; ++j) {
    if (best->within != nullptr && !best->within->contains(sorted_[static_cast<std::size_t>(j)])) {
      continue;
    }
    best->Offer((sorted_[static_cast<std::size_t>(j)] - q).squaredNorm(),
                order_[static_cast<std::size_t>(j)]);
  }
}

[[gnu::always_inline]] inline void NearestVoxelIndex::ScanRow(int x0, int x1, int y, int z,
                                                              bool ends_only,
                                                              const Eigen::Vector3d& q,
                                                              Best* best) const {
  const Eigen::Vector3i& size = occupied_.size;
  if (y < 0 || z < 0 || y >= size.y() || z >= size.z()) return;
  const std::size_t row = occupied_.Index(Eigen::Vector3i(0, y, z));
  const auto test = [&](int x) {
    if (x < 0 || x >= size.x()) return;
    const std::size_t i = row + static_cast<std::size_t>(x);
    if ((occupied_.words[i >> 6] >> (i & 63)) & 1) OfferCell(i, q, best);
  };
  if (ends_only) {  // the inside of the ring was scanned before
    test(x0);
    test(x1);
    return;
  }
  const int first = std::max(x0, 0), last = std::min(x1, size.x() - 1);
  for (int x = first; x <= last; x += 64) {
    const int length = std::min(64, last - x + 1);
    const std::size_t i = row + static_cast<std::size_t>(x);
    const std::size_t w = i >> 6;
    const unsigned b = static_cast<unsigned>(i & 63);
    std::uint64_t bits = occupied_.words[w] >> b;
    if (b != 0 && w + 1 < occupied_.words.size()) bits |= occupied_.words[w + 1] << (64 - b);
    if (length < 64) bits &= (std::uint64_t{1} << length) - 1;
    while (bits != 0) {
      OfferCell(i + static_cast<std::size_t>(__builtin_ctzll(bits)), q, best);
      bits &= bits - 1;
    }
  }
}

void NearestVoxelIndex::ScanCellHashed(const Eigen::Vector3i& cell, const Eigen::Vector3d& q,
                                       Best* best) const {
  auto it = cells_.find(PackCell(cell));
  if (it == cells_.end()) return;
  OfferPoints(it->second.first, it->second.first + it->second.second, q, best);
}

// Built twice, the right one picked when the program loads: Debian builds
// for the baseline x86-64, which has no popcount instruction, so elsewhere
// __builtin_popcountll is a call into libgcc, once per cell offered (OfferCell's
// rank). With the scan forced inline, each build has its own copy. Measured by
// callgrind on an fr_078_tidyup merge: 4 % fewer instructions in all.
[[gnu::target_clones("popcnt", "default")]] int NearestVoxelIndex::Nearest(
    const Eigen::Vector3d& q, double max_m, float* squared_m2, const Eigen::AlignedBox3d* within,
    double* others_m2) const {
  // The box need not be asked point by point when it holds every point that
  // could be accepted: those within max_m of q (grown by a micrometre, far
  // above rounding, so none at max_m is left out by it).
  if (within != nullptr) {
    const Eigen::Vector3d reach = Eigen::Vector3d::Constant(max_m + 1e-6);
    if (within->contains(Eigen::AlignedBox3d(q - reach, q + reach))) within = nullptr;
  }
  Best best{max_m * max_m, within};
  const Eigen::Vector3i c = Cell(q);
  // A query with no point within kReachCells (most of a wrong alignment's,
  // and those outside the overlap) is answered by one bit. The reach in
  // metres allows for rounding (3 x 0.1 m / 0.1 m is 3.0000000000000004).
  if (!near_.empty() && max_m <= kReachCells * cell_m_ * (1 + 1e-9) && !near_.Test(c)) {
    *squared_m2 = static_cast<float>(best.squared_m2);
    if (others_m2 != nullptr) *others_m2 = 0;  // no bound needed: nothing found
    return -1;
  }
  // Points beyond ring r are at least (r + margin) cells away, margin being
  // q's distance to the nearest face of its own cell, in cells.
  const Eigen::Vector3d in_cell = q / cell_m_ - c.cast<double>();
  const double margin = in_cell.cwiseMin(Eigen::Vector3d::Ones() - in_cell).minCoeff();
  const int max_ring = static_cast<int>(std::ceil(max_m / cell_m_));
  const Eigen::Vector3i o = c - occupied_.lo;
  double unscanned_m = 0;  // every point not offered yet is at least this far
  for (int ring = 0; ring <= max_ring; ++ring) {
    for (int dz = -ring; dz <= ring; ++dz) {
      for (int dy = -ring; dy <= ring; ++dy) {
        const bool face = std::abs(dy) == ring || std::abs(dz) == ring;
        if (dense()) {
          ScanRow(o.x() - ring, o.x() + ring, o.y() + dy, o.z() + dz, !face, q, &best);
          continue;
        }
        for (int dx = -ring; dx <= ring; dx += (face ? 1 : 2 * std::max(ring, 1))) {
          ScanCellHashed(c + Eigen::Vector3i(dx, dy, dz), q, &best);
        }
      }
    }
    // Slightly under the true bound, so rounding never skips an equal point.
    const double bound = (ring + std::max(margin, 0.0)) * cell_m_ * (1 - 1e-12);
    unscanned_m = bound;
    if (bound * bound > best.squared_m2) break;
  }
  *squared_m2 = static_cast<float>(best.squared_m2);
  if (others_m2 != nullptr) *others_m2 = std::min(best.others_m2, unscanned_m * unscanned_m);
  return best.index;
}

}  // namespace mapd::voxel
