#include "bench/voxel_crops.h"

#include <octomap/OcTree.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <sstream>
#include <vector>

#include "voxel/octree_reader.h"

namespace mapd::bench {
namespace {

constexpr int kKeyOffset = 32768;  // VoxelGrid keys = OctoMap keys - 32768

bool InKeyRange(const voxel::VoxelKey& k) {
  return (k.array() >= -kKeyOffset).all() && (k.array() < kKeyOffset).all();
}

// A slab of the source map: keys with lo <= key[axis] <= hi.
struct Slab {
  int axis = 0;
  int lo = 0, hi = 0;
  bool Contains(const voxel::VoxelKey& k) const { return k[axis] >= lo && k[axis] <= hi; }
};

// The source map's states inside a slab, dense over the box of the slab's
// occupied voxels and free cubes: the resampling probes every target voxel,
// and VoxelGrid::State walks up to 17 hash sets per probe.
class SlabStates {
 public:
  enum : std::uint8_t { kUnknown = 0, kFree = 1, kOccupied = 2 };

  SlabStates(const voxel::VoxelGrid& map, const Slab& slab) {
    lo_ = voxel::VoxelKey::Constant(kKeyOffset);
    hi_ = voxel::VoxelKey::Constant(-kKeyOffset);
    const auto clip = [&](voxel::VoxelKey* min_key, voxel::VoxelKey* max_key) {
      (*min_key)[slab.axis] = std::max((*min_key)[slab.axis], slab.lo);
      (*max_key)[slab.axis] = std::min((*max_key)[slab.axis], slab.hi);
      return ((*min_key).array() <= (*max_key).array()).all();
    };
    // Two passes over the free cubes: the box, then the fill.
    map.ForEachFreeCube([&](const voxel::VoxelKey& min_key, int edge) {
      voxel::VoxelKey a = min_key, b = min_key + voxel::VoxelKey::Constant(edge - 1);
      if (!clip(&a, &b)) return;
      lo_ = lo_.cwiseMin(a);
      hi_ = hi_.cwiseMax(b);
    });
    for (const voxel::VoxelKey& k : map.occupied_keys()) {
      if (!slab.Contains(k)) continue;
      lo_ = lo_.cwiseMin(k);
      hi_ = hi_.cwiseMax(k);
    }
    if ((lo_.array() > hi_.array()).any()) return;  // empty
    size_ = hi_ - lo_ + voxel::VoxelKey::Ones();
    state_.assign(static_cast<std::size_t>(size_.x()) * size_.y() * size_.z(), kUnknown);
    map.ForEachFreeCube([&](const voxel::VoxelKey& min_key, int edge) {
      voxel::VoxelKey a = min_key, b = min_key + voxel::VoxelKey::Constant(edge - 1);
      if (!clip(&a, &b)) return;
      for (int z = a.z(); z <= b.z(); ++z) {
        for (int y = a.y(); y <= b.y(); ++y) {
          for (int x = a.x(); x <= b.x(); ++x) state_[Index(voxel::VoxelKey(x, y, z))] = kFree;
        }
      }
    });
    for (const voxel::VoxelKey& k : map.occupied_keys()) {
      if (slab.Contains(k)) state_[Index(k)] = kOccupied;
    }
  }

  bool empty() const { return state_.empty(); }
  const voxel::VoxelKey& lo() const { return lo_; }
  const voxel::VoxelKey& hi() const { return hi_; }

  std::uint8_t At(const voxel::VoxelKey& k) const {
    if ((k.array() < lo_.array()).any() || (k.array() > hi_.array()).any()) return kUnknown;
    return state_[Index(k)];
  }

 private:
  std::size_t Index(const voxel::VoxelKey& k) const {
    const voxel::VoxelKey d = k - lo_;
    return (static_cast<std::size_t>(d.z()) * size_.y() + d.y()) * size_.x() + d.x();
  }

  voxel::VoxelKey lo_, hi_, size_ = voxel::VoxelKey::Zero();
  std::vector<std::uint8_t> state_;
};

struct Resampled {
  std::string bt;
  std::size_t occupied = 0, free = 0;
};

// Nearest-neighbour resampling of the slab of `map` under T_out_src (see the
// header): a target voxel takes the state of the source voxel containing
// T_out_src^-1 * (its centre). Every target voxel in the bounding box of the
// moved slab box is probed, so all of the slab's free space is carried over.
StatusOr<Resampled> Resample(const voxel::VoxelGrid& map, const Slab& slab,
                             const Eigen::Isometry3d& T_out_src) {
  const double res = map.resolution();
  const SlabStates states(map, slab);
  octomap::OcTree out(res);
  Resampled result;
  if (!states.empty()) {
    // The target box: the moved corners of the source box, one voxel of margin.
    Eigen::Vector3d tmin = Eigen::Vector3d::Constant(1e300), tmax = -tmin;
    for (int c = 0; c < 8; ++c) {
      const Eigen::Vector3d corner((c & 1 ? states.hi().x() + 1 : states.lo().x()) * res,
                                   (c & 2 ? states.hi().y() + 1 : states.lo().y()) * res,
                                   (c & 4 ? states.hi().z() + 1 : states.lo().z()) * res);
      const Eigen::Vector3d q = T_out_src * corner;
      tmin = tmin.cwiseMin(q);
      tmax = tmax.cwiseMax(q);
    }
    const voxel::VoxelKey tlo = map.PointToKey(tmin) - voxel::VoxelKey::Ones();
    const voxel::VoxelKey thi = map.PointToKey(tmax) + voxel::VoxelKey::Ones();
    if (!InKeyRange(tlo) || !InKeyRange(thi)) {
      return Status::FailedPrecondition("moved crop leaves OctoMap's key range");
    }
    const Eigen::Isometry3d T_src_out = T_out_src.inverse();
    const Eigen::Vector3d step = T_src_out.linear().col(0) * res;
    const float occ = out.getClampingThresMaxLog();
    const float fre = out.getClampingThresMinLog();
    // Key order (z, y, x): the tree is built the same way on every run.
    for (int z = tlo.z(); z <= thi.z(); ++z) {
      for (int y = tlo.y(); y <= thi.y(); ++y) {
        // Source position of each target centre along the row, in voxels.
        Eigen::Vector3d p = T_src_out * map.KeyToCentre(voxel::VoxelKey(tlo.x(), y, z));
        for (int x = tlo.x(); x <= thi.x(); ++x, p += step) {
          const Eigen::Vector3d v = p / res;
          const voxel::VoxelKey s(static_cast<int>(std::floor(v.x())),
                                  static_cast<int>(std::floor(v.y())),
                                  static_cast<int>(std::floor(v.z())));
          const std::uint8_t state = states.At(s);
          if (state == SlabStates::kUnknown) continue;
          const octomap::OcTreeKey key(static_cast<octomap::key_type>(x + kKeyOffset),
                                       static_cast<octomap::key_type>(y + kKeyOffset),
                                       static_cast<octomap::key_type>(z + kKeyOffset));
          const bool occupied = state == SlabStates::kOccupied;
          out.setNodeValue(key, occupied ? occ : fre, /*lazy_eval=*/true);
          ++(occupied ? result.occupied : result.free);
        }
      }
    }
  }
  out.updateInnerOccupancy();
  out.prune();
  std::ostringstream bytes;
  if (!out.writeBinary(bytes)) return Status::Internal("OcTree::writeBinary failed");
  result.bt = bytes.str();
  return result;
}

}  // namespace

Status CropParams::Validate() const {
  if (!disjoint && !(overlap > 0.0 && overlap < 1.0)) {
    return Status::InvalidArgument("overlap must be in (0, 1)");
  }
  if (!(gap_m >= 0.0 && gap_m <= 1000.0)) {
    return Status::InvalidArgument("gap_m must be in [0, 1000]");
  }
  if (max_occupied_per_crop < 500) {
    return Status::InvalidArgument("max_occupied_per_crop must be >= 500");
  }
  if (!(max_tilt_deg >= 0.0 && max_tilt_deg <= 90.0)) {
    return Status::InvalidArgument("max_tilt_deg must be in [0, 90]");
  }
  if (!(max_translation_m >= 0.0 && max_translation_m <= 1000.0)) {
    return Status::InvalidArgument("max_translation_m must be in [0, 1000]");
  }
  return Status::Ok();
}

StatusOr<CropPair> MakeCropPair(const voxel::VoxelGrid& map, const CropParams& params) {
  MAPD_RETURN_IF_ERROR(params.Validate());
  const std::vector<voxel::VoxelKey>& keys = map.occupied_keys();
  const std::size_t total = keys.size();
  if (total < 1000) {
    return Status::FailedPrecondition("map has " + std::to_string(total) +
                                      " occupied voxels, fewer than 1000");
  }
  CropPair pair;
  const voxel::VoxelKey extent = map.max_key() - map.min_key();
  pair.axis = extent.y() > extent.x() ? 1 : 0;
  std::vector<int> u;
  u.reserve(total);
  for (const voxel::VoxelKey& k : keys) u.push_back(k[pair.axis]);
  std::sort(u.begin(), u.end());

  std::mt19937_64 rng(params.seed);
  Slab slab_a{pair.axis, 0, 0}, slab_b{pair.axis, 0, 0};
  if (!params.disjoint) {
    // Ranks along the axis: A = [s, s + n), B = [s + n - m, s + 2n - m), m = overlap * n.
    const double f = params.overlap;
    const std::size_t n = std::min(params.max_occupied_per_crop,
                                   static_cast<std::size_t>(std::floor(total / (2.0 - f))));
    const std::size_t m = static_cast<std::size_t>(std::llround(f * n));
    const std::size_t span = 2 * n - m;
    std::uniform_int_distribution<std::size_t> start_dist(0, total - span);
    const std::size_t s = start_dist(rng);
    slab_a = {pair.axis, u[s], u[s + n - 1]};
    slab_b = {pair.axis, u[s + n - m], u[s + span - 1]};
  } else {
    // A = ranks [s, s + n); B = the n ranks from the first key gap voxels past
    // A's last layer. Draw s, then move it down until B fits.
    const int gap = static_cast<int>(std::ceil(params.gap_m / map.resolution()));
    const std::size_t n = std::min(params.max_occupied_per_crop, total * 2 / 5);
    std::uniform_int_distribution<std::size_t> start_dist(0, total - 2 * n);
    bool found = false;
    for (std::size_t s = start_dist(rng) + 1; s-- > 0 && !found;) {
      const int a_hi = u[s + n - 1];
      const std::size_t b_start = static_cast<std::size_t>(
          std::lower_bound(u.begin(), u.end(), a_hi + 1 + gap) - u.begin());
      if (b_start + n > total) continue;
      slab_a = {pair.axis, u[s], a_hi};
      slab_b = {pair.axis, u[b_start], u[b_start + n - 1]};
      found = true;
    }
    if (!found) {
      return Status::FailedPrecondition("map too short along its axis for two disjoint crops " +
                                        std::to_string(params.gap_m) + " m apart");
    }
  }

  Eigen::Vector3d sum_b = Eigen::Vector3d::Zero();
  for (const voxel::VoxelKey& k : keys) {
    const bool in_a = slab_a.Contains(k), in_b = slab_b.Contains(k);
    pair.occupied_a += in_a;
    pair.occupied_b += in_b;
    pair.shared += in_a && in_b;
    if (in_b) sum_b += map.KeyToCentre(k);
  }
  pair.achieved_overlap =
      static_cast<double>(pair.shared) / std::min(pair.occupied_a, pair.occupied_b);
  const Eigen::Vector3d c = sum_b / static_cast<double>(pair.occupied_b);

  // The motion: yaw anywhere, roll and pitch within the tilt bound, about B's
  // centroid; then a translation drawn uniformly in a ball (rejection sampling).
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  pair.yaw_deg = 180.0 * unit(rng);
  pair.roll_deg = params.max_tilt_deg * unit(rng);
  pair.pitch_deg = params.max_tilt_deg * unit(rng);
  Eigen::Vector3d t;
  do {
    t = Eigen::Vector3d(unit(rng), unit(rng), unit(rng));
  } while (t.squaredNorm() > 1.0);
  t *= params.max_translation_m;
  pair.translation_m = t.norm();
  const Eigen::Matrix3d R =
      (Eigen::AngleAxisd(pair.yaw_deg * M_PI / 180.0, Eigen::Vector3d::UnitZ()) *
       Eigen::AngleAxisd(pair.pitch_deg * M_PI / 180.0, Eigen::Vector3d::UnitY()) *
       Eigen::AngleAxisd(pair.roll_deg * M_PI / 180.0, Eigen::Vector3d::UnitX()))
          .toRotationMatrix();
  Eigen::Isometry3d T_b_map = Eigen::Isometry3d::Identity();
  T_b_map.linear() = R;
  T_b_map.translation() = c + t - R * c;
  pair.T_a_b = T_b_map.inverse();
  pair.centroid_b = c + t;

  StatusOr<Resampled> a = Resample(map, slab_a, Eigen::Isometry3d::Identity());
  if (!a.ok()) return a.status();
  StatusOr<Resampled> b = Resample(map, slab_b, T_b_map);
  if (!b.ok()) return b.status();
  pair.a_bt = std::move(a->bt);
  pair.b_bt = std::move(b->bt);
  pair.out_occupied_a = a->occupied;
  pair.out_free_a = a->free;
  pair.out_occupied_b = b->occupied;
  pair.out_free_b = b->free;
  return pair;
}

std::uint64_t TrialSeed(std::uint64_t base_seed, const std::string& map_file_name, double overlap,
                        int trial) {
  std::uint64_t name_hash = 14695981039346656037ULL;  // FNV-1a: std::hash is not specified
  for (unsigned char c : map_file_name) name_hash = (name_hash ^ c) * 1099511628211ULL;
  return base_seed * 1000003ULL + name_hash % 1000003ULL * 10007ULL +
         static_cast<std::uint64_t>(std::llround(overlap * 100)) * 101ULL +
         static_cast<std::uint64_t>(trial);
}

StatusOr<voxel::VoxelGrid> GridFromBytes(const std::string& bt_bytes) {
  StatusOr<voxel::OcTreePtr> tree = voxel::ReadOctree(bt_bytes);
  if (!tree.ok()) return tree.status();
  return voxel::VoxelGrid::FromOcTree(**tree);
}

StatusOr<voxel::VoxelGrid> ReadGridFile(const std::string& path) {
  StatusOr<voxel::OcTreePtr> tree = voxel::ReadOctreeFile(path);
  if (!tree.ok()) return tree.status();
  return voxel::VoxelGrid::FromOcTree(**tree);
}

StatusOr<BenchTrial> MakeBenchTrial(const voxel::VoxelGrid& map, const std::string& map_path,
                                    double overlap, int trial) {
  CropParams params;
  params.disjoint = overlap <= 0;
  if (!params.disjoint) params.overlap = overlap;
  params.seed = TrialSeed(1, map_path.substr(map_path.find_last_of('/') + 1), overlap, trial);
  StatusOr<CropPair> pair = MakeCropPair(map, params);
  if (!pair.ok()) return pair.status();
  StatusOr<voxel::VoxelGrid> a = GridFromBytes(pair->a_bt);
  if (!a.ok()) return a.status();
  StatusOr<voxel::VoxelGrid> b = GridFromBytes(pair->b_bt);
  if (!b.ok()) return b.status();
  return BenchTrial{std::move(*pair), std::move(*a), std::move(*b)};
}

int ForEachBenchTrial(const std::string& map_path, double overlap, int first, int count,
                      const std::function<void(int trial, const BenchTrial&)>& visit) {
  const StatusOr<voxel::VoxelGrid> map = ReadGridFile(map_path);
  if (!map.ok()) {
    std::fprintf(stderr, "%s: %s\n", map_path.c_str(), map.status().message().c_str());
    return 2;
  }
  for (int t = first; t < first + count; ++t) {
    const StatusOr<BenchTrial> trial = MakeBenchTrial(*map, map_path, overlap, t);
    if (!trial.ok()) {
      std::printf("trial %d: %s\n", t, trial.status().message().c_str());
      continue;
    }
    visit(t, *trial);
  }
  return 0;
}

double RotationErrorDeg(const Eigen::Isometry3d& est, const Eigen::Isometry3d& truth) {
  const Eigen::AngleAxisd d(est.linear().transpose() * truth.linear());
  return std::abs(d.angle()) * 180.0 / M_PI;
}

double TranslationErrorAt(const Eigen::Isometry3d& est, const Eigen::Isometry3d& truth,
                          const Eigen::Vector3d& point) {
  return (est * point - truth * point).norm();
}

}  // namespace mapd::bench
